/**
 * @class   vtkSegmentationSVDAGRenderSettings
 * @brief   the path tracer's settings, shared by the volume mapper and the image renderer
 *
 * Holds one svdag::render::RenderSettings (Rendering/core/svdag_render/RenderSettings.h: the one
 * definition of every setting and its default) and exposes its members under the same names.
 * Setters clamp to the core's ranges, like vtkSetClampMacro; each change bumps the MTime, which
 * the owning mapper or renderer includes in its own.
 *
 * Defaults (the core struct's member initializers, the one definition; a new object reports
 * them, e.g. GetLODAsString()): LOD auto, AutoLODPixels 1, SamplesPerPixel 1 (added per render
 * pass), MaximumBounces 4, Seed 0, NextEventEstimation on, Denoise on, Exposure 1, Background (0.1, 0.1,
 * 0.12, 1) linear RGBA (the volume mapper draws misses transparent instead), EnvironmentColor
 * (1, 1, 1), no EnvironmentMap, Sun off with direction (0.3, 0.4, 0.866), irradiance (3, 3, 3)
 * and angular radius 0.27 degrees, MaximumBlocksPerBLAS 0 (the device's limit),
 * DeviceMemoryLimit 0 (the device's memory), Shading voxel, Backend auto.
 *
 * The names of the LOD, shading and backend values (GetLODName(i) for i < GetNumberOfLODs(),
 * and so on) are the core's one list (svdag::render::Lods, lodName): the Python glue and the
 * command line read them from here.
 *
 * Clipping planes and cropping are not settings: the volume mapper (vtkAbstractMapper's
 * clipping planes, Cropping / CroppingRegionPlanes) and the image renderer
 * (vtkSegmentationSVDAGRenderer, the same names) own them and pass them to the core renderer
 * per frame.
 */
#ifndef vtkSegmentationSVDAGRenderSettings_h
#define vtkSegmentationSVDAGRenderSettings_h

#include "vtkObject.h"
#include "vtkSVDAGRenderingModule.h" // for export macro

#include <memory> // for std::unique_ptr

#ifndef __VTK_WRAP__
namespace svdag
{
namespace render
{
struct RenderSettings;
}
}
#endif

class VTKSVDAGRENDERING_EXPORT vtkSegmentationSVDAGRenderSettings : public vtkObject
{
public:
  static vtkSegmentationSVDAGRenderSettings* New();
  vtkTypeMacro(vtkSegmentationSVDAGRenderSettings, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** Level of detail: the block's box, the first non-empty 4^3 leaf, the voxel (lossless), or
   * per ray from the projected size of a voxel (LOD_AUTO). */
  enum
  {
    LOD_BLOCK = 0,
    LOD_LEAF = 1,
    LOD_VOXEL = 2,
    LOD_AUTO = 3
  };

  ///@{
  /** Level of detail, LOD_BLOCK .. LOD_AUTO (default LOD_AUTO); by name "block", "leaf",
   * "voxel" or "auto" (another name is reported as an error and changes nothing). An int outside
   * the range is clamped. */
  void SetLOD(int lod);
  void SetLOD(const char* name);
  int GetLOD() const;
  const char* GetLODAsString() const;
  /** The number of LOD values and the name of value `lod` (nullptr outside 0 .. count - 1). */
  static int GetNumberOfLODs();
  static const char* GetLODName(int lod);
  void SetLODToBlock() { this->SetLOD(LOD_BLOCK); }
  void SetLODToLeaf() { this->SetLOD(LOD_LEAF); }
  void SetLODToVoxel() { this->SetLOD(LOD_VOXEL); }
  void SetLODToAuto() { this->SetLOD(LOD_AUTO); }
  /** LOD_AUTO draws a block (leaf) where its 16 (4) voxels project to at most this many pixels. */
  void SetAutoLODPixels(double pixels);
  double GetAutoLODPixels() const;
  ///@}

  ///@{
  /** Samples per pixel each render pass adds to the accumulation (1 .. 65536). */
  void SetSamplesPerPixel(int samples);
  int GetSamplesPerPixel() const;
  /** Scattering events per path (0 .. 64; 0 shows only what emits light). */
  void SetMaximumBounces(int bounces);
  int GetMaximumBounces() const;
  /** Random seed: the same seed and settings give the same image. */
  void SetSeed(vtkTypeUInt32 seed);
  vtkTypeUInt32 GetSeed() const;
  /** Next-event estimation with multiple importance sampling; off: the estimator that finds
   * light only when a path escapes (same mean, slower to converge). */
  void SetNextEventEstimation(bool on);
  bool GetNextEventEstimation() const;
  vtkBooleanMacro(NextEventEstimation, bool);
  /** The label-aware denoiser on the displayed image (on by default): an edge-avoiding filter
   * guided by the traced label, depth and normal that never mixes radiance across labels and
   * fades out by itself as samples accumulate (DenoiseLayout.h). The accumulated samples, the
   * variance and the error estimate stay the raw path tracer's. */
  void SetDenoise(bool on);
  bool GetDenoise() const;
  vtkBooleanMacro(Denoise, bool);
  /** Scale of the linear color before the tone curve (1e-6 .. 1e6). */
  void SetExposure(double exposure);
  double GetExposure() const;
  ///@}

  ///@{
  /** Linear RGBA of camera samples that hit nothing (image renderer only). */
  void SetBackground(double r, double g, double b, double a);
  void SetBackground(const double rgba[4]) { this->SetBackground(rgba[0], rgba[1], rgba[2], rgba[3]); }
  void GetBackground(double rgba[4]) const;
  ///@}

  ///@{
  /** Environment: constant linear radiance, or the scale of the map. */
  void SetEnvironmentColor(double r, double g, double b);
  void SetEnvironmentColor(const double rgb[3]) { this->SetEnvironmentColor(rgb[0], rgb[1], rgb[2]); }
  void GetEnvironmentColor(double rgb[3]) const;
  /** An equirectangular OpenEXR environment map (longitude along x from +x towards +y, +z up);
   * nullptr or "" for the constant environment. Read on the next render (errors there). */
  void SetEnvironmentMap(const char* path);
  const char* GetEnvironmentMap() const;
  ///@}

  ///@{
  /** The sun: a disk light of SunAngularRadius degrees (0: a delta light) in SunDirection
   * (towards the sun, world), with SunIrradiance (linear RGB at normal incidence). */
  void SetSun(bool on);
  bool GetSun() const;
  vtkBooleanMacro(Sun, bool);
  void SetSunDirection(double x, double y, double z);
  void SetSunDirection(const double d[3]) { this->SetSunDirection(d[0], d[1], d[2]); }
  void GetSunDirection(double d[3]) const;
  void SetSunIrradiance(double r, double g, double b);
  void SetSunIrradiance(const double e[3]) { this->SetSunIrradiance(e[0], e[1], e[2]); }
  void GetSunIrradiance(double e[3]) const;
  void SetSunAngularRadius(double degrees);
  double GetSunAngularRadius() const;
  ///@}

  ///@{
  /** Most blocks per bottom-level acceleration structure; 0 uses the device's limit. Smaller
   * values trace slower: they exist to exercise the split (tests). */
  void SetMaximumBlocksPerBLAS(vtkTypeInt64 blocks);
  vtkTypeInt64 GetMaximumBlocksPerBLAS() const;
  ///@}

  ///@{
  /** Most bytes of device memory the renderer may hold; 0 (the default) uses the device's memory
   * heaps. For a GPU shared with other programs: a volume that does not fit is refused with an
   * error naming the bytes it needs and the bytes available. Negative values are taken as 0. */
  void SetDeviceMemoryLimit(vtkTypeInt64 bytes);
  vtkTypeInt64 GetDeviceMemoryLimit() const;
  ///@}

  /** Shading normal: SHADING_VOXEL (the entry face's, blocky) or SHADING_SMOOTH (estimated from
   * the hit label's occupancy around the hit point, svdag/SmoothNormal.h). The hit itself
   * (position, label, depth) stays the lossless voxel surface either way. */
  enum
  {
    SHADING_VOXEL = 0,
    SHADING_SMOOTH = 1
  };

  ///@{
  /** Shading, SHADING_VOXEL (default) or SHADING_SMOOTH; by name "voxel" or "smooth" (another
   * name is reported as an error and changes nothing). An int outside the range is clamped. */
  void SetShading(int shading);
  void SetShading(const char* name);
  int GetShading() const;
  const char* GetShadingAsString() const;
  static int GetNumberOfShadings();
  static const char* GetShadingName(int shading);
  void SetShadingToVoxel() { this->SetShading(SHADING_VOXEL); }
  void SetShadingToSmooth() { this->SetShading(SHADING_SMOOTH); }
  ///@}

  /** How rays find the blocks: BACKEND_AUTO (default: per device, compute on lavapipe and on
   * devices without ray tracing, the ray tracing pipeline on GPUs with it), BACKEND_RT (the ray
   * tracing pipeline over a BVH of block boxes) or BACKEND_COMPUTE (a compute shader walking the
   * volume's 16^3 cell grid; no BVH, hiding a label rebuilds nothing). The same images either
   * way. A renderer reports what it uses (GetBackendInUse). */
  enum
  {
    BACKEND_AUTO = 0,
    BACKEND_RT = 1,
    BACKEND_COMPUTE = 2
  };

  ///@{
  /** Backend, BACKEND_AUTO (default), BACKEND_RT or BACKEND_COMPUTE; by name "auto", "rt" or
   * "compute" (another name is reported as an error and changes nothing). An int outside the
   * range is clamped. */
  void SetBackend(int backend);
  void SetBackend(const char* name);
  int GetBackend() const;
  const char* GetBackendAsString() const;
  static int GetNumberOfBackends();
  static const char* GetBackendName(int backend);
  void SetBackendToAuto() { this->SetBackend(BACKEND_AUTO); }
  void SetBackendToRT() { this->SetBackend(BACKEND_RT); }
  void SetBackendToCompute() { this->SetBackend(BACKEND_COMPUTE); }
  ///@}

  /** Copies every setting of another object. */
  void DeepCopy(vtkSegmentationSVDAGRenderSettings* other);

#ifndef __VTK_WRAP__
  const svdag::render::RenderSettings& GetCoreSettings() const { return *this->Settings; }
#endif

protected:
  vtkSegmentationSVDAGRenderSettings();
  ~vtkSegmentationSVDAGRenderSettings() override;

private:
  vtkSegmentationSVDAGRenderSettings(const vtkSegmentationSVDAGRenderSettings&) = delete;
  void operator=(const vtkSegmentationSVDAGRenderSettings&) = delete;

  std::unique_ptr<svdag::render::RenderSettings> Settings;
};

#endif
