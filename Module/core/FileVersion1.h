// Reading .svdag files of format 1.0 (private to File.cpp): their leaf references have no
// symmetry field (Layout.h), so the loaded streams are re-laid out in today's layout.
#pragma once

#include "svdag/Volume.h"

namespace svdag
{
namespace file
{
// Rewrites v's streams, read from a 1.0 file with their 1.0 widths, in today's layout: every
// leaf reference (index << 1 | complement) gains the identity symmetry, which moves the mid
// nodes, so root references (offsets into the mid stream) and block records (offsets into the
// root stream) are rewritten with the widths the moved offsets need. Checks every node against
// its stream's end and every reference against a node start; throws std::runtime_error naming
// what is wrong. The result still needs Volume::validate.
void upgradeVersion1(Volume& v);
} // namespace file
} // namespace svdag
