#include "vtkSegmentationVolumeReader.h"

#include "vtkErrorCode.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkSVDAGParallel.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkUnsignedCharArray.h"

#include "svdagSVDAGFileSlabSource.h"
#include "svdagSlabSourceFactory.h"

#include "svdag/Builder.h"

#include <algorithm>
#include <exception>
#include <future>
#include <memory>
#include <new>

vtkStandardNewMacro(vtkSegmentationVolumeReader);

struct vtkSegmentationVolumeReader::Internals
{
  std::unique_ptr<svdagSlabSource> Source;
  // How many of Source's warnings were passed on already (RequestInformation's).
  size_t WarningsReported = 0;
};

vtkSegmentationVolumeReader::vtkSegmentationVolumeReader()
  : Internal(new Internals)
{
}

vtkSegmentationVolumeReader::~vtkSegmentationVolumeReader()
{
  delete this->Internal;
  this->SetFileName(nullptr);
  this->SetDatasetName(nullptr);
  this->SetInputArray(nullptr);
}

vtkCxxSetObjectMacro(vtkSegmentationVolumeReader, InputArray, vtkUnsignedCharArray);

int vtkSegmentationVolumeReader::CanReadFile(const char* fileName)
{
  return fileName && !svdagDetectFileFormat(fileName).empty() ? 1 : 0;
}

const char* vtkSegmentationVolumeReader::GetFileExtensions()
{
  return ".nrrd .nhdr .seg.nrrd .mha .mhd .vti .nii .nii.gz .hdr .img .tif .tiff .h5 .hdf5 "
         ".hdf .svdag";
}

const char* vtkSegmentationVolumeReader::GetDescriptiveName()
{
  return "Segmentation label volume";
}

namespace
{
// A source's message without the "FILE: " it starts with (the reader names the file itself).
std::string withoutFileName(const std::string& message, const char* fileName)
{
  const std::string prefix = std::string(fileName) + ": ";
  return message.compare(0, prefix.size(), prefix) == 0 ? message.substr(prefix.size()) : message;
}

svdagSlabSourceOptions sourceOptions(const char* datasetName, bool castFloatLabels)
{
  svdagSlabSourceOptions options;
  if (datasetName)
    options.datasetName = datasetName;
  options.castFloatLabels = castFloatLabels;
  return options;
}

// Passes the source's warnings from the `reported`-th on to VTK's warning mechanism (a
// WarningEvent, which vtksvdag turns into a Python warning).
void reportWarnings(vtkObject* reader, const svdagSlabSource& source, const char* name, size_t& reported)
{
  for (; reported < source.warnings().size(); ++reported)
    vtkWarningWithObjectMacro(
      reader, "Reading " << name << ": " << withoutFileName(source.warnings()[reported], name));
}

// What error messages call the input.
const char* InputArrayName = "the input array";
}

const char* vtkSegmentationVolumeReader::InputName() const
{
  return this->ReadFromInputString ? InputArrayName : (this->FileName ? this->FileName : "");
}

bool vtkSegmentationVolumeReader::CheckInputGiven()
{
  const bool given = this->ReadFromInputString ? this->InputArray != nullptr
                                               : (this->FileName && *this->FileName);
  if (!given)
  {
    vtkErrorMacro(<< (this->ReadFromInputString ? "ReadFromInputString is on but no InputArray is set."
                                               : "No FileName set."));
    this->SetErrorCode(vtkErrorCode::NoFileNameError);
  }
  return given;
}

std::unique_ptr<svdagSlabSource> vtkSegmentationVolumeReader::OpenSource()
{
  if (!this->ReadFromInputString)
    return svdagOpenSlabSource(
      this->FileName, sourceOptions(this->DatasetName, this->CastFloatLabels));
  const auto* bytes = this->InputArray->GetPointer(0);
  return std::unique_ptr<svdagSlabSource>(new svdagSVDAGFileSlabSource(
    bytes, size_t(this->InputArray->GetNumberOfValues()), InputArrayName));
}

int vtkSegmentationVolumeReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* out)
{
  this->SetErrorCode(vtkErrorCode::NoError);
  this->FileFormat.clear();
  this->Internal->Source.reset();
  // On failure RequestData does not run: empty the output here, so that it never shows the
  // volume of a previous file.
  auto fail = [&](unsigned long code) {
    this->SetErrorCode(code);
    if (vtkSegmentationSVDAG* output = vtkSegmentationSVDAG::GetData(out))
      output->Initialize();
    return 0;
  };
  if (!this->CheckInputGiven())
    return fail(vtkErrorCode::NoFileNameError);
  const char* name = this->InputName();
  try
  {
    // Opening a source reads and checks the whole header.
    this->Internal->Source = this->OpenSource();
    this->FileFormat = this->Internal->Source->formatName();
    this->Internal->WarningsReported = 0;
    reportWarnings(this, *this->Internal->Source, name, this->Internal->WarningsReported);
  }
  catch (const svdagReadError& e)
  {
    vtkErrorMacro(
      "Cannot read " << name << ": " << withoutFileName(e.what(), name));
    return fail(e.code());
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Cannot read " << name << ": " << e.what());
    return fail(vtkErrorCode::UnknownError);
  }
  // Parallel pipelines (ParaView's ranks) ask for pieces: each is read and compressed alone.
  out->GetInformationObject(0)->Set(vtkAlgorithm::CAN_HANDLE_PIECE_REQUEST(), 1);
  return 1;
}

int vtkSegmentationVolumeReader::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* out)
{
  vtkSegmentationSVDAG* output = vtkSegmentationSVDAG::GetData(out);
  if (!output)
  {
    vtkErrorMacro("Missing output.");
    return 0;
  }
  output->Initialize();
  this->SetErrorCode(vtkErrorCode::NoError);
  if (!this->CheckInputGiven())
    return 0;
  const char* name = this->InputName();

  const svdag::BuildOptions options = this->GetBuildOptions();

  try
  {
    // The source RequestInformation opened, or a fresh one (streams that decompress cannot
    // rewind, so a source serves one RequestData).
    size_t warningsReported = this->Internal->Source ? this->Internal->WarningsReported : 0;
    std::unique_ptr<svdagSlabSource> source = std::move(this->Internal->Source);
    if (!source)
      source = this->OpenSource();
    reportWarnings(this, *source, name, warningsReported);
    this->FileFormat = source->formatName();
    const svdag::Geometry& geometry = source->geometry();
    const svdag::ScalarType type = source->scalarType();

    // The piece asked for: z-slices [zBegin, zEnd), whole slabs.
    int piece = 0, pieces = 1, zBegin = 0, zEnd = 0;
    if (!vtkSegmentationSVDAGAlgorithm::GetRequestedPiece(
          out->GetInformationObject(0), geometry.dims[2], piece, pieces, zBegin, zEnd))
    {
      vtkErrorMacro("Cannot read " << name << ": piece " << piece << " of " << pieces
                                   << " was requested.");
      return 0;
    }
    if (zBegin == zEnd && geometry.dims[2] > 0)
    {
      this->UpdateProgress(1.0);
      return 1; // more pieces than slabs: this one is empty
    }

    // A compressed file whose labels need no change is passed through as it is (whole).
    if (const auto volume = source->compressedVolume(); volume && pieces == 1)
    {
      uint64_t background = 0;
      svdag::scalarStore(type, &background, 0, options.background);
      if (options.excluded.empty() && svdag::scalarLoad(type, &background, 0) == volume->background)
      {
        output->SetVolume(volume);
        this->UpdateProgress(1.0);
        return 1;
      }
    }

    // Two slabs are the reader's working memory: the source fills one while the builder
    // compresses the other, so a decompressing source (gzip NRRD, .nii.gz) and the builder each
    // keep a core busy. A volume whose two slabs alone exceed the machine's memory (absurd but
    // well-formed dimensions) is refused before anything is allocated.
    const uint64_t slabBytes = uint64_t(geometry.dims[0]) * uint64_t(geometry.dims[1]) *
      uint64_t(std::min(svdag::Builder::SlabDepth, geometry.dims[2])) *
      uint64_t(svdag::scalarSize(type));
    const uint64_t memory = svdagPhysicalMemoryBytes();
    if (memory > 0 && slabBytes > memory / 2)
    {
      vtkErrorMacro("Cannot read " << name << ": two slabs of 16 z-slices take "
                                   << 2 * slabBytes << " bytes, more than this machine's memory.");
      this->SetErrorCode(vtkErrorCode::OutOfDiskSpaceError);
      return 0;
    }
    svdag::Builder builder(
      geometry.zRange(zBegin, zEnd), type, options, vtkSVDAGParallelFor());
    // Not value-initialised: the source overwrites every byte.
    std::unique_ptr<uint8_t[]> slabs[2];
    slabs[0].reset(new uint8_t[size_t(slabBytes)]);
    if (zEnd > svdag::Builder::SlabDepth)
      slabs[1].reset(new uint8_t[size_t(slabBytes)]);
    // Slabs alternate between the two buffers.
    auto slabAt = [&slabs](int32_t z0) {
      return slabs[(z0 / svdag::Builder::SlabDepth) % 2].get();
    };
    // Slab z0's read, on a thread of its own. Sources serve slabs in order from the first
    // (compressed streams cannot seek), one read at a time: the next starts once this one is
    // taken. Its exception is rethrown where it is taken; one left pending (an abort, a failed
    // compression) is waited for when the future goes.
    auto readAhead = [&](int32_t z0) {
      const int32_t nz = std::min(svdag::Builder::SlabDepth, zEnd - z0);
      uint8_t* slab = slabAt(z0);
      return std::async(
        std::launch::async, [&source, z0, nz, slab] { source->readSlab(z0, nz, slab); });
    };
    // Slabs before the piece are read and dropped, so a piece costs reading time, never more
    // memory.
    std::future<void> next;
    if (zEnd > 0)
      next = readAhead(0);
    for (int32_t z0 = 0; z0 < zEnd; z0 += svdag::Builder::SlabDepth)
    {
      const int32_t nz = std::min(svdag::Builder::SlabDepth, zEnd - z0);
      next.get();
      if (z0 + nz < zEnd)
        next = readAhead(z0 + nz);
      if (this->GetAbortExecute())
      {
        vtkWarningMacro("Reading " << name << " was aborted.");
        return 0;
      }
      if (z0 >= zBegin)
        builder.addSlab(z0 - zBegin, nz, slabAt(z0));
      this->UpdateProgress(double(z0 + nz) / zEnd);
    }
    reportWarnings(this, *source, name, warningsReported);
    output->SetVolume(std::make_shared<const svdag::Volume>(builder.finish()));
  }
  catch (const svdagReadError& e)
  {
    vtkErrorMacro(
      "Cannot read " << name << ": " << withoutFileName(e.what(), name));
    this->SetErrorCode(e.code());
    return 0;
  }
  catch (const std::bad_alloc&)
  {
    vtkErrorMacro("Out of memory reading " << name << ".");
    this->SetErrorCode(vtkErrorCode::OutOfDiskSpaceError);
    return 0;
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Cannot compress " << name << ": " << e.what());
    this->SetErrorCode(vtkErrorCode::UnknownError);
    return 0;
  }
  return 1;
}

void vtkSegmentationVolumeReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "DatasetName: " << (this->DatasetName ? this->DatasetName : "(none)") << "\n";
  os << indent << "CastFloatLabels: " << (this->CastFloatLabels ? "On" : "Off") << "\n";
  os << indent << "ReadFromInputString: " << (this->ReadFromInputString ? "On" : "Off") << "\n";
  os << indent << "InputArray: " << this->InputArray << "\n";
  os << indent << "FileFormat: " << this->FileFormat << "\n";
}
