/**
 * @class   vtkSegmentationSVDAGRenderer
 * @brief   path-traces a vtkSegmentationSVDAG with Vulkan ray tracing into an image
 *
 * Rays find blocks through a BLAS of block boxes; a custom intersection shader walks each
 * block's DAG with the same traversal code as the CPU ray caster. Every Render() adds
 * SamplesPerPixel path-traced samples per pixel to a progressive accumulation, which restarts
 * whenever anything that changes the image changes (camera, size, LOD, materials, visibility,
 * lighting, bounces, NEE, seed, background; ResetAccumulation() forces it). The output is a
 * vtkImageData of Width x Height points with the point-data arrays
 *   "Color"  4 x unsigned char  display color: per channel x = Exposure * HDR, Reinhard's curve
 *                               x / (1 + x), then sRGB; alpha = HDR alpha
 *   "HDR"    4 x float          linear RGBA, the mean of the accumulated samples; a camera sample
 *                               that hits nothing counts as the Background color (the
 *                               environment lights the scene, the camera does not see it)
 *   "Depth"  float              world distance from the camera along the ray; FLT_MAX on a miss
 *   "Label"  int                label index + 1 (0: background)
 *   "Normal" 3 x float          world-space unit normal of the face entered (0 on a miss and
 *                               where the camera is inside the hit voxel)
 * Depth, Label and Normal come from the un-jittered pixel-center ray: pixel (x, y), y = 0 the
 * bottom row, is the point x + Width * y. Its ray starts at the camera
 * position with the direction normalize(F + u * tan(a/2) * Width/Height * R + v * tan(a/2) * U),
 * u = 2 (x + 0.5) / Width - 1, v = 2 (y + 0.5) / Height - 1, F the unit direction to the focal
 * point, R = normalize(F x ViewUp), U = R x F and a the vertical view angle (VTK camera semantics).
 * Samples jitter the point uniformly inside the pixel.
 *
 * Path tracing: per-label materials (by label INDEX; defaults: base color from a hash of the
 * index, roughness 0.6, metallic 0, transmission 0, IOR 1.5, specular 0.5, visible), a constant
 * or equirectangular OpenEXR environment, an optional sun (a disk light), next-event estimation
 * with multiple importance sampling (or the plain estimator), Russian roulette. A fixed Seed gives
 * the same image. A material edit is a buffer upload; visibility 0 removes the label's blocks from
 * the BVH. Known limitation: a ray starting inside a solid has no exit point in the traversal, so
 * refracted paths end at the surface (transmission darkens instead of showing the inside).
 *
 * The camera is set with SetCameraPosition/FocalPoint/ViewUp/ViewAngle, or framed around the
 * whole volume with ResetCamera(azimuth, elevation, zoom); a camera never set is reset on the
 * first Render(). Hidden labels (by label index) are left out of the BVH, which is rebuilt on the
 * next Render() (cheap: the volume is not uploaded again).
 *
 * The Vulkan device is chosen on the first Render(): a GPU with ray tracing if present, else a
 * CPU implementation (lavapipe); the environment variable SVDAG_VK_DEVICE=<substring> forces
 * one, SVDAG_VK_VALIDATION=1 enables the validation layer. Render() returns 0 and reports the
 * reason with vtkErrorMacro (for example no device with ray tracing: the message names each
 * device found and what it lacks).
 */
#ifndef vtkSegmentationSVDAGRenderer_h
#define vtkSegmentationSVDAGRenderer_h

#include "vtkObject.h"
#include "vtkSVDAGRenderingModule.h" // for export macro

#include <memory> // for std::unique_ptr

class vtkImageData;
class vtkSegmentationSVDAG;

class VTKSVDAGRENDERING_EXPORT vtkSegmentationSVDAGRenderer : public vtkObject
{
public:
  static vtkSegmentationSVDAGRenderer* New();
  vtkTypeMacro(vtkSegmentationSVDAGRenderer, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** Level of detail: the block's box, the first non-empty 4^3 leaf, the voxel (lossless), or
   * per ray from the projected size of a voxel (AUTO). */
  enum
  {
    LOD_BLOCK = 0,
    LOD_LEAF = 1,
    LOD_VOXEL = 2,
    LOD_AUTO = 3
  };

  ///@{
  /** The volume to render. */
  void SetInputData(vtkSegmentationSVDAG* volume);
  vtkSegmentationSVDAG* GetInput();
  ///@}

  ///@{
  /** Image size in pixels (default 256 x 256). */
  vtkSetClampMacro(Width, int, 1, 16384);
  vtkGetMacro(Width, int);
  vtkSetClampMacro(Height, int, 1, 16384);
  vtkGetMacro(Height, int);
  ///@}

  ///@{
  /** Level of detail, LOD_BLOCK .. LOD_AUTO (default LOD_VOXEL). */
  vtkSetClampMacro(LOD, int, LOD_BLOCK, LOD_AUTO);
  vtkGetMacro(LOD, int);
  ///@}

  ///@{
  /** LOD_AUTO draws a block (leaf) where its 16 (4) voxels project to at most this many pixels
   * at the block's entry distance, else voxels (default 1). */
  vtkSetClampMacro(AutoLODPixels, double, 1e-6, 1e6);
  vtkGetMacro(AutoLODPixels, double);
  ///@}

  ///@{
  /** The camera, in world coordinates, with VTK's semantics (view angle: vertical, degrees). */
  void SetCameraPosition(double x, double y, double z);
  void SetCameraPosition(const double p[3]) { this->SetCameraPosition(p[0], p[1], p[2]); }
  vtkGetVector3Macro(CameraPosition, double);
  void SetCameraFocalPoint(double x, double y, double z);
  void SetCameraFocalPoint(const double p[3]) { this->SetCameraFocalPoint(p[0], p[1], p[2]); }
  vtkGetVector3Macro(CameraFocalPoint, double);
  void SetCameraViewUp(double x, double y, double z);
  void SetCameraViewUp(const double v[3]) { this->SetCameraViewUp(v[0], v[1], v[2]); }
  vtkGetVector3Macro(CameraViewUp, double);
  void SetCameraViewAngle(double degrees);
  vtkGetMacro(CameraViewAngle, double);
  ///@}

  /**
   * Frames the whole volume like vtkRenderer::ResetCamera (from +z, +y up, the bounding sphere
   * fitting the view angle), then orbits by azimuth and elevation (degrees) and moves closer by
   * zoom (> 0; 2 halves the distance). Returns 0 (and reports an error) without an input.
   */
  int ResetCamera(double azimuth = 0.0, double elevation = 0.0, double zoom = 1.0);

  ///@{
  /** Labels (by index in the volume's label table) left out of the image. */
  void HideLabel(vtkIdType index);
  void ShowLabel(vtkIdType index);
  void ShowAllLabels();
  bool IsLabelHidden(vtkIdType index) const;
  ///@}

  ///@{
  /** Most blocks per bottom-level acceleration structure (BLAS); 0 (default) uses the device's
   * limit (16,777,215 on lavapipe), and volumes with more visible blocks are split into several
   * BLAS. Smaller values trace slower: they exist to exercise the split (tests). */
  vtkSetClampMacro(MaximumBlocksPerBLAS, vtkTypeInt64, 0, VTK_INT_MAX);
  vtkGetMacro(MaximumBlocksPerBLAS, vtkTypeInt64);
  /** Number of BLAS of the last Render(). */
  int GetNumberOfBLAS() const;
  ///@}

  ///@{
  /** Linear RGBA written where no block is hit (default 0.1, 0.1, 0.12, 1). */
  vtkSetVector4Macro(Background, double);
  vtkGetVector4Macro(Background, double);
  ///@}

  ///@{
  /** Samples per pixel each Render() adds (default 1). */
  vtkSetClampMacro(SamplesPerPixel, int, 1, 65536);
  vtkGetMacro(SamplesPerPixel, int);
  /** Scattering events per path (default 4; 0 shows only what emits light). */
  vtkSetClampMacro(MaximumBounces, int, 0, 64);
  vtkGetMacro(MaximumBounces, int);
  /** Random seed (default 0): the same seed and settings give the same image. */
  vtkSetMacro(Seed, vtkTypeUInt32);
  vtkGetMacro(Seed, vtkTypeUInt32);
  /** Next-event estimation with multiple importance sampling (default on); off is the estimator
   * that finds light only when a path escapes (slower to converge, same mean). */
  vtkSetMacro(NextEventEstimation, bool);
  vtkGetMacro(NextEventEstimation, bool);
  vtkBooleanMacro(NextEventEstimation, bool);
  /** Scale of the linear color before the tone curve of the Color output (default 1). */
  vtkSetClampMacro(Exposure, double, 1e-6, 1e6);
  vtkGetMacro(Exposure, double);
  ///@}

  ///@{
  /** Environment: constant linear radiance (default 1, 1, 1), or the scale of the map. */
  vtkSetVector3Macro(EnvironmentColor, double);
  vtkGetVector3Macro(EnvironmentColor, double);
  /** An equirectangular OpenEXR environment map (longitude along x from +x towards +y, +z up);
   * nullptr or "" for the constant environment. Read on the next Render() (errors there). */
  vtkSetStringMacro(EnvironmentMap);
  vtkGetStringMacro(EnvironmentMap);
  ///@}

  ///@{
  /** The sun: a disk light of the given angular radius (degrees, 0: a point-like delta light)
   * in SunDirection (towards the sun, world), with SunIrradiance (linear RGB at normal incidence).
   * Off by default. */
  vtkSetMacro(Sun, bool);
  vtkGetMacro(Sun, bool);
  vtkBooleanMacro(Sun, bool);
  vtkSetVector3Macro(SunDirection, double);
  vtkGetVector3Macro(SunDirection, double);
  vtkSetVector3Macro(SunIrradiance, double);
  vtkGetVector3Macro(SunIrradiance, double);
  vtkSetClampMacro(SunAngularRadius, double, 0.0, 89.0);
  vtkGetMacro(SunAngularRadius, double);
  ///@}

  ///@{
  /** Material of a label, by its INDEX in the volume's label table (an index outside the table
   * is an error at Render()). Colors are linear RGB; roughness, metallic, transmission and
   * specular are in [0, 1] (specular 0.5: 4% reflectance at normal incidence, 0: none); IOR > 0;
   * visibility false removes the label from the image. */
  void SetLabelColor(vtkIdType index, double r, double g, double b);
  void SetLabelRoughness(vtkIdType index, double roughness);
  void SetLabelMetallic(vtkIdType index, double metallic);
  void SetLabelTransmission(vtkIdType index, double transmission);
  void SetLabelIOR(vtkIdType index, double ior);
  void SetLabelSpecular(vtkIdType index, double specular);
  void SetLabelEmission(vtkIdType index, double r, double g, double b);
  void SetLabelVisibility(vtkIdType index, bool visible);
  /** Every label back to its default material. */
  void ResetLabelMaterials();
  ///@}

  /** Renders one pass (SamplesPerPixel samples per pixel, added to the accumulation) into the
   * output. Returns 1 on success, 0 on failure (vtkErrorMacro). */
  int Render();

  /** Starts a new accumulation on the next Render(). */
  void ResetAccumulation();

  /** Writes the current image: the Color output as PNG (".png") or linear HDR, depth (Z) and
   * label as OpenEXR (".exr"). Returns 1 on success, 0 on failure (vtkErrorMacro). */
  int WriteImage(const char* path);

  /** The image of the last successful Render() (empty before). */
  vtkImageData* GetOutput();

  ///@{
  /** The Vulkan device used ("" before the first Render()), the seconds of the last upload and
   * BVH build, the milliseconds of the last frame and the bytes of the BVH. */
  const char* GetDeviceName() const;
  double GetSetupSeconds() const;
  double GetLastFrameMilliseconds() const;
  vtkTypeInt64 GetBLASBytes() const;
  vtkTypeInt64 GetTLASBytes() const;
  ///@}

  ///@{
  /** Samples per pixel in the current image, and the seconds of tracing that produced it. */
  int GetAccumulatedSamples() const;
  double GetRenderSeconds() const;
  /** BVH builds (volume uploads and visibility changes) and ray tracing pipeline builds (feature
   * changes) since the device was created: material edits rebuild neither. */
  vtkTypeInt64 GetNumberOfBVHBuilds() const;
  vtkTypeInt64 GetNumberOfPipelineBuilds() const;
  ///@}

protected:
  vtkSegmentationSVDAGRenderer();
  ~vtkSegmentationSVDAGRenderer() override;

  int Width = 256;
  int Height = 256;
  int LOD = LOD_VOXEL;
  double AutoLODPixels = 1;
  vtkTypeInt64 MaximumBlocksPerBLAS = 0;
  double CameraPosition[3] = { 0, 0, 1 };
  double CameraFocalPoint[3] = { 0, 0, 0 };
  double CameraViewUp[3] = { 0, 1, 0 };
  double CameraViewAngle = 30;
  double Background[4] = { 0.1, 0.1, 0.12, 1 };
  int SamplesPerPixel = 1;
  int MaximumBounces = 4;
  vtkTypeUInt32 Seed = 0;
  bool NextEventEstimation = true;
  double Exposure = 1;
  double EnvironmentColor[3] = { 1, 1, 1 };
  char* EnvironmentMap = nullptr;
  bool Sun = false;
  double SunDirection[3] = { 0.3, 0.4, 0.866 };
  double SunIrradiance[3] = { 3, 3, 3 };
  double SunAngularRadius = 0.27;

private:
  vtkSegmentationSVDAGRenderer(const vtkSegmentationSVDAGRenderer&) = delete;
  void operator=(const vtkSegmentationSVDAGRenderer&) = delete;

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
