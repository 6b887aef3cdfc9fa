#include "vtkSegmentationSVDAGWriter.h"

#include "vtkAlgorithm.h"
#include "vtkErrorCode.h"
#include "vtkInformation.h"
#include "vtkObjectFactory.h"
#include "vtkSVDAGParallel.h"
#include "vtkSegmentationSVDAG.h"

#include "svdag/File.h"

#include <algorithm>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkSegmentationSVDAGWriter);

// The defaults are the core's (svdag::WriteOptions).
vtkSegmentationSVDAGWriter::vtkSegmentationSVDAGWriter()
  : CompressionLevel(svdag::WriteOptions().zstdLevel)
  , FormatVersion(svdag::WriteOptions().formatVersion)
{
}

vtkSegmentationSVDAGWriter::~vtkSegmentationSVDAGWriter()
{
  this->SetFileName(nullptr);
}

int vtkSegmentationSVDAGWriter::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkSegmentationSVDAG");
  return 1;
}

vtkUnsignedCharArray* vtkSegmentationSVDAGWriter::GetOutputBytes()
{
  return this->OutputBytes;
}

void vtkSegmentationSVDAGWriter::WriteData()
{
  this->OutputBytes->Initialize();
  if (!this->WriteToOutputString && (!this->FileName || !*this->FileName))
  {
    vtkErrorMacro("No FileName set.");
    this->SetErrorCode(vtkErrorCode::NoFileNameError);
    return;
  }
  vtkSegmentationSVDAG* input = vtkSegmentationSVDAG::SafeDownCast(this->GetInput());
  if (!input || !input->HasVolume())
  {
    vtkErrorMacro("The input holds no compressed volume; nothing written"
      << (this->WriteToOutputString ? std::string() : std::string(" to ") + this->FileName) << ".");
    this->SetErrorCode(vtkErrorCode::UnknownError);
    return;
  }

  this->UpdateProgress(0.0);
  svdag::WriteOptions options;
  options.zstdLevel = this->CompressionLevel;
  options.formatVersion = this->FormatVersion;
  // The core throws; VTK code reports. Each failure kind maps to the matching VTK error code.
  try
  {
    if (this->WriteToOutputString)
    {
      const std::vector<uint8_t> bytes =
        svdag::serialize(*input->GetVolume(), options, vtkSVDAGParallelFor());
      this->OutputBytes->SetNumberOfValues(vtkIdType(bytes.size()));
      std::copy(bytes.begin(), bytes.end(), this->OutputBytes->GetPointer(0));
    }
    else
      svdag::writeFile(*input->GetVolume(), this->FileName, options, vtkSVDAGParallelFor());
  }
  catch (const svdag::FileOpenError& e)
  {
    vtkErrorMacro(<< e.what());
    this->SetErrorCode(vtkErrorCode::CannotOpenFileError);
    return;
  }
  catch (const svdag::FileWriteError& e)
  {
    vtkErrorMacro(<< e.what());
    this->SetErrorCode(vtkErrorCode::OutOfDiskSpaceError);
    return;
  }
  catch (const std::exception& e)
  {
    this->OutputBytes->Initialize();
    vtkErrorMacro("Cannot write " << (this->WriteToOutputString ? "the volume" : this->FileName)
                                  << ": " << e.what());
    this->SetErrorCode(vtkErrorCode::UnknownError);
    return;
  }
  this->UpdateProgress(1.0);
}

void vtkSegmentationSVDAGWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "CompressionLevel: " << this->CompressionLevel << "\n";
  os << indent << "FormatVersion: " << this->FormatVersion << "\n";
  os << indent << "WriteToOutputString: " << (this->WriteToOutputString ? "On" : "Off") << "\n";
  os << indent << "OutputBytes: " << this->OutputBytes->GetNumberOfValues() << " bytes\n";
}
