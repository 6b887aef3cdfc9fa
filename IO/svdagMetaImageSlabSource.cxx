#include "svdagMetaImageSlabSource.h"

#include "vtkMetaImageReader.h"

#include <cctype>
#include <cstdio>
#include <string>

svdagMetaImageSlabSource::svdagMetaImageSlabSource(const std::string& fileName)
  : svdagVTKImageSlabSource(vtkSmartPointer<vtkMetaImageReader>::New(), fileName, true)
{
  vtkMetaImageReader::SafeDownCast(this->Reader)->SetFileName(fileName.c_str());
  this->open();
}

bool svdagMetaImageSlabSource::canRead(const std::string& fileName)
{
  // A MetaImage header is "Key = Value" lines; look for the keys every image has, in the first
  // 4 KiB, and only in text (a binary file never passes).
  std::FILE* f = std::fopen(fileName.c_str(), "rb");
  if (!f)
    return false;
  char buffer[4096];
  const size_t n = std::fread(buffer, 1, sizeof(buffer), f);
  std::fclose(f);
  std::string text(buffer, n);
  // The header ends where the inline data starts (after "ElementDataFile = LOCAL").
  const size_t local = text.find("ElementDataFile");
  if (local != std::string::npos)
  {
    const size_t eol = text.find('\n', local);
    text.resize(eol == std::string::npos ? text.size() : eol);
  }
  for (unsigned char c : text)
  {
    if (!std::isprint(c) && !std::isspace(c))
      return false;
  }
  auto hasKey = [&](const char* key) {
    for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1))
    {
      if (at == 0 || text[at - 1] == '\n')
      {
        const size_t eq = text.find_first_not_of(" \t", at + std::string(key).size());
        if (eq != std::string::npos && text[eq] == '=')
          return true;
      }
    }
    return false;
  };
  return hasKey("NDims") && hasKey("DimSize") && hasKey("ElementType");
}
