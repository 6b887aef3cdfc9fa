#include "svdag_render/ImageFiles.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

namespace svdag
{
namespace render
{
namespace
{
void putBigEndian32(std::vector<uint8_t>& out, uint32_t v)
{
  for (int shift = 24; shift >= 0; shift -= 8)
    out.push_back(uint8_t(v >> shift));
}

// A PNG chunk: length, type, data, CRC-32 of type and data.
void putChunk(std::vector<uint8_t>& out, const char type[4], const std::vector<uint8_t>& data)
{
  putBigEndian32(out, uint32_t(data.size()));
  const size_t typeStart = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  const uLong crc = crc32(0L, out.data() + typeStart, uInt(out.size() - typeStart));
  putBigEndian32(out, uint32_t(crc));
}

void writeWhole(const std::string& path, const std::vector<uint8_t>& bytes)
{
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!file)
    throw std::runtime_error("cannot open '" + path + "' for writing");
  if (std::fwrite(bytes.data(), 1, bytes.size(), file.get()) != bytes.size())
    throw std::runtime_error("cannot write '" + path + "'");
  if (std::fclose(file.release()) != 0)
    throw std::runtime_error("cannot write '" + path + "'");
}

void checkImage(const Image& image)
{
  const size_t pixels = size_t(image.width) * image.height;
  if (pixels == 0 || image.color.size() != pixels || image.hdr.size() != 4 * pixels ||
    image.depth.size() != pixels || image.label.size() != pixels)
    throw std::runtime_error("no rendered image to write");
}
} // namespace

void writePng(const Image& image, const std::string& path)
{
  checkImage(image);
  const uint32_t w = image.width, h = image.height;
  // Scanlines top first, each with filter type 0 (none); color bytes are R, G, B, A.
  std::vector<uint8_t> raw;
  raw.reserve(size_t(h) * (1 + 4 * size_t(w)));
  for (uint32_t row = 0; row < h; ++row)
  {
    raw.push_back(0);
    const uint32_t* line = image.color.data() + size_t(h - 1 - row) * w;
    for (uint32_t x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c)
        raw.push_back(uint8_t(line[x] >> (8 * c)));
  }
  uLongf packedSize = compressBound(uLong(raw.size()));
  std::vector<uint8_t> packed(packedSize);
  if (compress2(packed.data(), &packedSize, raw.data(), uLong(raw.size()), 6) != Z_OK)
    throw std::runtime_error("zlib could not compress the PNG image data");
  packed.resize(packedSize);

  std::vector<uint8_t> png = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
  std::vector<uint8_t> header;
  putBigEndian32(header, w);
  putBigEndian32(header, h);
  header.insert(header.end(), { 8, 6, 0, 0, 0 }); // 8 bits, RGBA, deflate, filter 0, no interlace
  putChunk(png, "IHDR", header);
  putChunk(png, "IDAT", packed);
  putChunk(png, "IEND", {});
  writeWhole(path, png);
}

void writeExr(const Image& image, const std::string& path)
{
  checkImage(image);
  const int w = int(image.width), h = int(image.height);
  // Planar, top-first copies: R, G, B, A, Z (float) and label (uint).
  std::vector<float> planes[5];
  std::vector<uint32_t> labels(size_t(w) * h);
  for (auto& p : planes)
    p.resize(size_t(w) * h);
  for (int y = 0; y < h; ++y)
  {
    for (int x = 0; x < w; ++x)
    {
      const size_t src = size_t(h - 1 - y) * w + x, dst = size_t(y) * w + x;
      for (int c = 0; c < 4; ++c)
        planes[c][dst] = image.hdr[4 * src + c];
      planes[4][dst] = image.depth[src];
      labels[dst] = image.label[src];
    }
  }
  try
  {
    Imf::Header header(w, h);
    const char* names[5] = { "R", "G", "B", "A", "Z" };
    Imf::FrameBuffer frame;
    for (int c = 0; c < 5; ++c)
    {
      header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
      frame.insert(names[c],
        Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[c].data()), sizeof(float),
          sizeof(float) * size_t(w)));
    }
    header.channels().insert("label", Imf::Channel(Imf::UINT));
    frame.insert("label",
      Imf::Slice(Imf::UINT, reinterpret_cast<char*>(labels.data()), sizeof(uint32_t),
        sizeof(uint32_t) * size_t(w)));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(h);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("cannot write EXR '" + path + "': " + e.what());
  }
}

} // namespace render
} // namespace svdag
