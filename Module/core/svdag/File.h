// The .svdag file format: a Volume on disk, checked on load so that a truncated or corrupt file
// gives a FileError, never a crash, an out-of-bounds read or a huge allocation.
//
// Format versions 4.0 (the default), 3.0 and 2.0 share the header and section table below; 1.0
// files are read too (see FileMajorVersion). A 4.0 file holds one section, the DAG as byte
// streams (DagStreams.h: node headers, reference flags, shared nodes' indices, leaf masks, block
// cells and labels, label values, each under zstd), from which loading lays the volume out again
// and derives the block bounds and label totals; a 3.0 file holds the coded volume
// (CodedVolume.h: label values, and per cell its labels and their occupancy, arithmetic-coded),
// from which loading rebuilds the volume as a build of the same voxels lays it out; a 2.0 file
// holds the Volume's own parts (sections 1-5), which load as they are. IO/README.md documents
// them. Every integer is little-endian, every real an IEEE-754 binary64 stored as its 64-bit
// pattern, little-endian; fields are written one by one, never as memory images.
//
//   offset size  field
//   0      8     magic  89 53 56 44 41 47 0D 0A  ("\x89SVDAG\r\n": the high byte catches 7-bit
//                       transfers, CR LF catches line-ending conversion, a short file fails here)
//   8      2     major version (4, 3 or 2): a reader rejects a major version it does not know
//   10     2     minor version (0): additions a reader can ignore (more sections)
//   12     12    dims: 3 x int32, each >= 1
//   24     24    spacing[3] (float64), finite and > 0
//   48     24    origin[3] (float64), finite
//   72     72    direction[9] (float64, row-major index-to-physical), finite
//   144    4     scalar type (uint32, svdag::ScalarType: 0 int8 .. 7 uint64)
//   148    8     background label (uint64 pattern, sign-extended for signed types)
//   156    20    field widths (5 x uint32, each <= 32): cell, label, root ref, mid ref, leaf ref
//   176    40    counts (5 x uint64): labels, blocks, root nodes, mid nodes, leaves (3.0: the
//                rebuilt volume's widths and counts, which loading checks; 4.0: the decoded
//                volume's, its pools in first-use order)
//   216    4     number of sections S (uint32, at most 64)
//   220    36*S  section table, one entry per section:
//                  id (uint32), codec (uint32: 0 none, 1 zstd), offset (uint64, from the start of
//                  the file), stored size (uint64, bytes in the file), raw size (uint64, bytes
//                  after decompression), crc32 of the raw bytes (uint32, zlib's crc32)
//   220+36*S 4   crc32 of every byte before it (magic, header and section table)
//
// Sections follow the header in any order, without overlap. Raw contents:
//   1 labels  per label: value (uint64 pattern), voxels (uint64), bounds (6 x int32:
//             xmin, xmax, ymin, ymax, zmin, zmax, inclusive)            -> 40 bytes per label
//   2 blocks  the bit-packed block records as uint32 words (Layout.h), without the padding word
//   3 roots   the root node stream as uint32 words, without the padding word
//   4 mids    the mid node stream as uint32 words, without the padding word
//   5 leaves  the 4^3 leaf masks, uint64 each
//   6 coded   (3.0) the coded volume, stored as the range coder wrote it (codec 0)
//   7 streams (4.0) per DAG stream (DagStreams.h, in its order) its stored and raw sizes as
//             varints, then the streams, each a zstd frame (level 19) or, where that is not
//             smaller, its raw bytes (stored size == raw size); the section itself codec 0
// 2.0 requires sections 1-5, 3.0 section 6 and 4.0 section 7, once each; sections with other
// ids are skipped (minor additions).
// The raw size of sections 1, 2 and 5 must be what the counts imply; the node streams must hold
// between 16 and 16 + 8 * refBits bits per node. The reader re-adds the padding words.
//
// Loading is one pass over the file: header, table, then each section is decompressed (a zstd
// frame must decode to exactly its declared raw size; the output buffer grows with the bytes
// actually produced, so a false size cannot reserve memory), checked against its crc32, decoded,
// and finally the whole Volume is checked with Volume::validate(): content as well as checksums
// (every reference at a node start, blocks sorted by cell and label with bounds inside their cell
// and the volume, each block's occupancy non-empty and inside its bounds, blocks of a cell
// disjoint, the label table's counts and bounds equal to what the blocks hold), in time linear in
// the file size. A 3.0 file's coded section is checked against its crc32 and decoded, every
// decision checked against what the writer can have coded, and the rebuilt volume's widths and
// counts against the header's. A loaded file may still describe a volume too large to decode
// densely: see checkDecodeMemory in svdag/Decoder.h.
//
// Writing a 3.0 or 4.0 file decodes its section again and compares every block's cell, label and
// occupancy with the volume's before anything is written.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace svdag
{

// Any failure to read or write a .svdag file; what() names the file part that is wrong.
struct FileError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};
// writeFile could not create or open the file (the VTK writer maps it to CannotOpenFileError).
struct FileOpenError : FileError
{
  using FileError::FileError;
};
// writeFile could not write every byte (disk full, I/O error; OutOfDiskSpaceError in VTK).
struct FileWriteError : FileError
{
  using FileError::FileError;
};

// The newest version written (4.0: the DAG streams). 2.0: leaf references carry a symmetry
// (Layout.h). 1.0 files (leaf references without one) are
// read and re-laid out on load (FileVersion1.h).
constexpr uint16_t FileMajorVersion = 4;
constexpr uint16_t FileMinorVersion = 0;
constexpr size_t FileMagicSize = 8;
extern const uint8_t FileMagic[FileMagicSize];

struct WriteOptions
{
  int zstdLevel = 3; // format 2: 1..22; 0 stores the sections uncompressed
  // 4: the DAG's byte streams under zstd, smaller than CSGV's files and loaded in a fraction of
  // a build's time. 3: the coded volume, the smallest file (about half of 4's); loading rebuilds
  // the DAG from it, about a build's time. 2: the layout's sections (zstd at zstdLevel), read by
  // readers older than 3.0 too.
  int formatVersion = 4;
};

// `parallel` runs format 3's chunks (CodedVolume.h) side by side; the bytes and volumes do not
// depend on it. Files store the pooled form of a volume (Compact.h): writers take either form,
// readers validate the pooled form they read and return it compact.

// The whole file in memory. Throws FileError if the volume does not validate or the level or
// version is not one written.
std::vector<uint8_t> serialize(
  const Volume& volume, const WriteOptions& options = {}, const ParallelFor& parallel = sequentialFor);
// Parses and validates a whole file held in memory. Throws FileError.
Volume deserialize(const uint8_t* data, size_t size, const ParallelFor& parallel = sequentialFor);
inline Volume deserialize(const std::vector<uint8_t>& bytes, const ParallelFor& parallel = sequentialFor)
{
  return deserialize(bytes.data(), bytes.size(), parallel);
}

// Writes through a temporary file next to `path`, renamed at the end, so a failed write never
// leaves a partial file under the final name. Throws FileOpenError, FileWriteError or FileError.
void writeFile(const Volume& volume, const std::string& path, const WriteOptions& options = {},
  const ParallelFor& parallel = sequentialFor);
// Reads and validates a file. Throws FileError (also when the file cannot be opened).
Volume readFile(const std::string& path, const ParallelFor& parallel = sequentialFor);
// True if the file starts with the .svdag magic (nothing else is checked).
bool isSVDAGFile(const std::string& path);

} // namespace svdag
