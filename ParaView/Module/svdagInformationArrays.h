// The numbers ParaView's Information panel shows for a vtkSegmentationSVDAG. vtkPVDataInformation
// knows nothing of the compressed volume (it reports its memory size and its field data), so the
// plugin's sources attach the numbers to the output as one-value field data arrays.
#ifndef svdagInformationArrays_h
#define svdagInformationArrays_h

class vtkSegmentationSVDAG;

namespace svdag
{
namespace paraview
{
// Field data arrays "LabelCount" (stored labels, background excluded), "CompressedBytes" (what
// vtksvdag's stats() calls bytes_total) and "BitsPerVoxel" (8 * CompressedBytes / voxels),
// replacing earlier ones of those names.
void AddInformationArrays(vtkSegmentationSVDAG* volume);
}
}

#endif
