#include "svdagVTIImageSlabSource.h"

#include "vtkNew.h"
#include "vtkXMLImageDataReader.h"

svdagVTIImageSlabSource::svdagVTIImageSlabSource(const std::string& fileName)
  : svdagVTKImageSlabSource(vtkSmartPointer<vtkXMLImageDataReader>::New(), fileName, false)
{
  vtkXMLImageDataReader::SafeDownCast(this->Reader)->SetFileName(fileName.c_str());
  this->open();
}

bool svdagVTIImageSlabSource::canRead(const std::string& fileName)
{
  vtkNew<vtkXMLImageDataReader> reader;
  return reader->CanReadFile(fileName.c_str()) != 0;
}
