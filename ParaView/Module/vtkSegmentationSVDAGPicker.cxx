#include "vtkSegmentationSVDAGPicker.h"

#include "vtkObjectFactory.h"
#include "vtkSegmentationSVDAGRepresentation.h"

vtkStandardNewMacro(vtkSegmentationSVDAGPicker);

vtkSegmentationSVDAGPicker::vtkSegmentationSVDAGPicker() = default;
vtkSegmentationSVDAGPicker::~vtkSegmentationSVDAGPicker() = default;

void vtkSegmentationSVDAGPicker::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Representation: " << static_cast<void*>(this->Representation.GetPointer())
     << "\n";
}

void vtkSegmentationSVDAGPicker::SetRepresentation(vtkSegmentationSVDAGRepresentation* r)
{
  if (this->Representation != r)
  {
    this->Representation = r;
    this->Modified();
  }
}

void vtkSegmentationSVDAGPicker::SetPickPixel(double x, double y)
{
  if (this->Representation)
  {
    this->Representation->SetPickPixel(x, y);
  }
}

int vtkSegmentationSVDAGPicker::GetPickedHit()
{
  return this->Representation ? this->Representation->GetPickedHit() : 0;
}

vtkTypeInt64 vtkSegmentationSVDAGPicker::GetPickedLabel()
{
  return this->Representation ? this->Representation->GetPickedLabel() : 0;
}

int vtkSegmentationSVDAGPicker::GetAccumulatedSamples()
{
  return this->Representation ? this->Representation->GetAccumulatedSamples() : 0;
}
