#include "svdagVTIImageSlabSource.h"

#include "vtkNew.h"
#include "vtkXMLImageDataReader.h"

svdagVTIImageSlabSource::svdagVTIImageSlabSource(const std::string& fileName)
  : svdagVTKImageSlabSource(vtkSmartPointer<vtkXMLImageDataReader>::New(), fileName)
{
  vtkXMLImageDataReader::SafeDownCast(this->reader())->SetFileName(fileName.c_str());
  this->open();
  this->checkGeometry(fileName);
}

bool svdagVTIImageSlabSource::canRead(const std::string& fileName)
{
  vtkNew<vtkXMLImageDataReader> reader;
  return reader->CanReadFile(fileName.c_str()) != 0;
}
