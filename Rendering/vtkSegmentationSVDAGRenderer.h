/**
 * @class   vtkSegmentationSVDAGRenderer
 * @brief   path-traces a vtkSegmentationSVDAG with Vulkan into an image (an algorithm)
 *
 * A vtkImageAlgorithm: one input port, a vtkSegmentationSVDAG (SetInputConnection from a reader
 * or from vtkImageDataToSegmentationSVDAG, or SetInputData), one output, a vtkImageData of
 * Width x Height x 1 points (whole extent 0..Width-1, 0..Height-1, 0..0). Each execution renders
 * PassesPerRender passes (default 1), each Settings->SamplesPerPixel path-traced samples per
 * pixel added to a progressive
 * accumulation, which restarts whenever anything that changes the image changed (input volume,
 * camera, size, settings other than Exposure and SamplesPerPixel, label properties;
 * ResetAccumulation() forces it). Like any algorithm it re-executes on Update() when the input
 * or anything it holds changed (its MTime includes the settings' and the label properties');
 * Render() forces one more pass (Modified() then Update()) and returns 1 on success, 0 when an
 * error was reported (vtkErrorMacro).
 *
 * The output's point-data arrays:
 *   "Color"  4 x unsigned char  display color (the active scalars): per channel
 *                               x = Exposure * HDR, Reinhard's curve x / (1 + x), then sRGB;
 *                               alpha = HDR alpha
 *   "HDR"    4 x float          linear RGBA, the mean of the accumulated samples; a camera sample
 *                               that hits nothing counts as the Background color (the
 *                               environment lights the scene, the camera does not see it)
 *   "Depth"  float              world distance from the camera along the ray; FLT_MAX on a miss
 *   "Label"  int                label index + 1 (0: background); the index is that of the
 *                               volume's label table (vtkSegmentationSVDAG::NewLabelValues)
 *   "Normal" 3 x float          world-space unit shading normal: the face entered's, or the
 *                               smooth estimate with Settings Shading smooth (0 on a miss and
 *                               where the camera is inside the hit voxel)
 *   "FaceNormal" 3 x float      world-space unit normal of the face entered (0 likewise)
 * Depth, Label and Normal come from the un-jittered pixel-center ray: pixel (x, y), y = 0 the
 * bottom row, is the point x + Width * y. Its ray starts at the camera
 * position with the direction normalize(F + u * tan(a/2) * Width/Height * R + v * tan(a/2) * U),
 * u = 2 (x + 0.5) / Width - 1, v = 2 (y + 0.5) / Height - 1, F the unit direction to the focal
 * point, R = normalize(F x ViewUp), U = R x F and a the vertical view angle (VTK camera semantics).
 * Samples jitter the point uniformly inside the pixel.
 *
 * Settings: GetSettings() is a vtkSegmentationSVDAGRenderSettings, the same class (the same
 * names and defaults: LOD, AutoLODPixels, SamplesPerPixel, MaximumBounces, Seed,
 * NextEventEstimation, Exposure, Background, EnvironmentColor, EnvironmentMap, Sun*,
 * MaximumBlocksPerBLAS) as vtkSegmentationSVDAGVolumeMapper's; SetSettings shares one object
 * between several renderers and mappers. A bad value is reported where it is set (the settings
 * clamp, and reject a zero sun direction); an environment map that cannot be read is an error of
 * the next pass.
 *
 * Appearance: GetLabelProperties() is a vtkSegmentationSVDAGLabelProperties, keyed by the
 * ORIGINAL label values (SetColor takes display sRGB, converted to the path tracer's linear RGB;
 * roughness, metallic, transmission, IOR, specular, emission, opacity, visibility, a lookup
 * table; a value the volume does not hold is ignored); SetLabelProperties shares it with a
 * mapper. Labels never set keep the defaults (base color from a hash of the label index,
 * roughness 0.6, metallic 0, transmission 0, IOR 1.5, specular 0.5, visible). A material edit is
 * a buffer upload; a hidden label (visibility false or opacity 0) leaves the BVH, which is
 * rebuilt on the next pass (cheap: the volume is not uploaded again).
 *
 * Path tracing: a constant or equirectangular OpenEXR environment, an optional sun (a disk
 * light), next-event estimation with multiple importance sampling (or the plain estimator),
 * Russian roulette. A fixed Seed gives the same image. Known limitation: transmission is
 * thin-walled (a transmitted ray continues straight through the label, Shading.h), and where a
 * label continues into the next 16^3 cell the ray meets one more surface event at the cell face.
 *
 * Clipping and cropping, owned here (not by the settings), with vtkSegmentationSVDAGVolumeMapper's
 * names: clipping planes (vtkPlane objects in world coordinates, each keeping the half-space its
 * normal points to, at most GetMaximumNumberOfClippingPlanes(), 6) and an axis-aligned crop box
 * (Cropping, CroppingRegionPlanes xmin, xmax, ymin, ymax, zmin, zmax; world). Every ray (camera,
 * shadow, bounce) is clipped, so a cut-away part is neither seen nor casts a shadow; where the
 * kept region cuts a labelled voxel the cut face is drawn (at block / leaf LOD the block / leaf
 * box's cross-section) with the plane's normal facing the viewer, "Label" and "Depth" those of
 * the cut face. A change restarts the accumulation (no BVH rebuild); moving a plane (vtkPlane::
 * SetOrigin) counts as a change. Bad planes (a 7th, a zero or non-finite normal, a non-finite
 * origin) are an error of the next pass.
 *
 * The camera is set with SetCameraPosition/FocalPoint/ViewUp/ViewAngle, or framed around the
 * whole volume with ResetCamera(azimuth, elevation, zoom); a camera never set is framed on the
 * first pass.
 *
 * The Vulkan device is chosen on the first pass: a GPU if present (one with ray tracing first),
 * else a CPU implementation (lavapipe); the environment variable SVDAG_VK_DEVICE=<substring>
 * forces one, SVDAG_VK_VALIDATION=1 enables the validation layer. The backend (Settings'
 * Backend: the ray tracing pipeline or the compute cell-grid walk) is per device by default;
 * GetBackendInUse tells which one runs. A pass that fails reports the reason with vtkErrorMacro
 * (for example no usable device: the message names each device found and what it lacks; or the
 * rt backend on a device without ray tracing) and leaves an empty output.
 */
#ifndef vtkSegmentationSVDAGRenderer_h
#define vtkSegmentationSVDAGRenderer_h

#include "vtkImageAlgorithm.h"
#include "vtkSVDAGRenderingModule.h" // for export macro

#include <memory> // for std::unique_ptr

class vtkPlane;
class vtkUnsignedIntArray;
class vtkPlaneCollection;
class vtkSegmentationSVDAG;
class vtkSegmentationSVDAGLabelProperties;
class vtkSegmentationSVDAGRenderSettings;

class VTKSVDAGRENDERING_EXPORT vtkSegmentationSVDAGRenderer : public vtkImageAlgorithm
{
public:
  static vtkSegmentationSVDAGRenderer* New();
  vtkTypeMacro(vtkSegmentationSVDAGRenderer, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  vtkMTimeType GetMTime() override;

  /** The input volume (nullptr without one; through a connection: after an update). */
  vtkSegmentationSVDAG* GetInput();

  ///@{
  /** The path tracer's settings (never null; SetSettings ignores nullptr). */
  vtkSegmentationSVDAGRenderSettings* GetSettings();
  void SetSettings(vtkSegmentationSVDAGRenderSettings* settings);
  ///@}

  ///@{
  /** Per-label appearance by label value (never null; SetLabelProperties ignores nullptr). */
  vtkSegmentationSVDAGLabelProperties* GetLabelProperties();
  void SetLabelProperties(vtkSegmentationSVDAGLabelProperties* properties);
  ///@}

  ///@{
  /** Image size in pixels (default 256 x 256). */
  vtkSetClampMacro(Width, int, 1, 16384);
  vtkGetMacro(Width, int);
  vtkSetClampMacro(Height, int, 1, 16384);
  vtkGetMacro(Height, int);
  ///@}

  ///@{
  /** Passes one execution traces (default 1, at most 65536), each adding
   * Settings->SamplesPerPixel samples: the denoiser (Settings Denoise) filters only the last,
   * the one the output shows, so several passes in one Render() cost less than as many
   * Render() calls. GetPassMilliseconds(i): the frame time of pass i of the last execution
   * (the last one's includes the denoiser), 0 for an i outside 0 .. PassesPerRender - 1. */
  vtkSetClampMacro(PassesPerRender, int, 1, 65536);
  vtkGetMacro(PassesPerRender, int);
  double GetPassMilliseconds(int pass) const;
  ///@}

  ///@{
  /** Guided upsampling (default 1: off, at most 8): the paths are traced at
   * ceil(Width / r) x ceil(Height / r) pixels and shown at the output's size, guided by every
   * output pixel's own pixel-center label and depth (Label, Depth and Normal stay exact; see
   * svdag_render/UpsampleLayout.h). A change restarts the accumulation. */
  vtkSetClampMacro(TraceReduction, int, 1, 8);
  vtkGetMacro(TraceReduction, int);
  ///@}

  ///@{
  /** Step statistics (compute backend; default off): the passes count, per traced pixel,
   * where its rays spend their steps, in a pipeline variant compiled with the counters (off,
   * they are compiled out). GetStepCounts after a pass: 8 components per pixel (named: rays,
   * cells, cells_with_blocks, blocks, dag_walks, dag_steps, shadow_rays, hits; Traversal.h's
   * SVDAG_STAT_*), summed over the last pass's rays, pixels in output order; no tuples where
   * nothing was counted (off, or the ray tracing backend). The array belongs to the renderer. */
  vtkSetMacro(StepStatistics, vtkTypeBool);
  vtkGetMacro(StepStatistics, vtkTypeBool);
  vtkBooleanMacro(StepStatistics, vtkTypeBool);
  vtkUnsignedIntArray* GetStepCounts();
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

  ///@{
  /**
   * Clipping planes (world), as vtkAbstractMapper's: AddClippingPlane and RemoveClippingPlane
   * (nullptr is ignored), RemoveAllClippingPlanes, SetClippingPlanes (shares a collection;
   * nullptr for none) and GetClippingPlanes (nullptr before a plane is added).
   */
  void AddClippingPlane(vtkPlane* plane);
  void RemoveClippingPlane(vtkPlane* plane);
  void RemoveAllClippingPlanes();
  void SetClippingPlanes(vtkPlaneCollection* planes);
  vtkPlaneCollection* GetClippingPlanes();
  /** The most clipping planes a pass takes (6). */
  static int GetMaximumNumberOfClippingPlanes();
  ///@}

  ///@{
  /**
   * The crop box (world), used while Cropping is on (default off): only what lies inside is
   * drawn, with cut faces like clipping planes. SetCroppingRegionPlanes reports an error for an
   * inverted (min > max) or non-finite box and keeps the previous one (default 0, 1, 0, 1, 0, 1).
   */
  vtkSetMacro(Cropping, vtkTypeBool);
  vtkGetMacro(Cropping, vtkTypeBool);
  vtkBooleanMacro(Cropping, vtkTypeBool);
  void SetCroppingRegionPlanes(
    double xmin, double xmax, double ymin, double ymax, double zmin, double zmax);
  void SetCroppingRegionPlanes(const double bounds[6])
  {
    this->SetCroppingRegionPlanes(bounds[0], bounds[1], bounds[2], bounds[3], bounds[4], bounds[5]);
  }
  vtkGetVector6Macro(CroppingRegionPlanes, double);
  ///@}

  /**
   * Frames the whole volume like vtkRenderer::ResetCamera (from +z, +y up, the bounding sphere
   * fitting the view angle), then orbits by azimuth and elevation (degrees) and moves closer by
   * zoom (> 0; 2 halves the distance). Updates the input first when it is connected. Returns 0
   * (and reports an error) without an input.
   */
  int ResetCamera(double azimuth = 0.0, double elevation = 0.0, double zoom = 1.0);

  /** Renders one more pass (Modified(), then Update()). Returns 1 on success, 0 when an error
   * was reported (vtkErrorMacro). */
  int Render();

  /** Starts a new accumulation on the next pass. */
  void ResetAccumulation();

  /** Writes the current image: the Color output as PNG (".png") or linear HDR, depth (Z) and
   * label as OpenEXR (".exr"). Returns 1 on success, 0 on failure (vtkErrorMacro). */
  int WriteImage(const char* path);

  ///@{
  /** The Vulkan device used ("" before the first pass), the seconds of the last upload and
   * BVH build, the milliseconds of the last frame, the bytes of the BVH and the number of BLAS
   * (volumes with more visible blocks than MaximumBlocksPerBLAS are split into several). */
  const char* GetDeviceName() const;
  double GetSetupSeconds() const;
  double GetLastFrameMilliseconds() const;
  vtkTypeInt64 GetBLASBytes() const;
  vtkTypeInt64 GetTLASBytes() const;
  int GetNumberOfBLAS() const;
  /** Bytes of the smooth-shading neighbour table on the device (0 until a smooth pass). */
  vtkTypeInt64 GetNeighbourTableBytes() const;
  ///@}

  ///@{
  /** The backend in use, "rt" or "compute" ("" before the first pass, or where Settings asks for
   * one the device cannot run), and the bytes of device memory held, in all (GetDeviceBytes) and
   * by part: the volume's encoding (block and DAG streams), what the backend finds blocks with
   * (BLAS, TLAS and the primitive map; or the compute backend's cell grid and hidden-label bits),
   * per-label materials and environment tables, and the images (outputs, accumulation, ray
   * limits); 0 before the first pass. */
  const char* GetBackendInUse() const;
  vtkTypeInt64 GetDeviceBytes() const;
  vtkTypeInt64 GetEncodingBytes() const;
  vtkTypeInt64 GetAccelerationBytes() const;
  vtkTypeInt64 GetMaterialBytes() const;
  vtkTypeInt64 GetImageBytes() const;
  ///@}

  ///@{
  /** Every mapper and renderer of a process shares one Vulkan device (created on first use,
   * released with its last user). GetDeviceUsers: how many use it now (0: none exists);
   * GetDeviceId: which device this one uses (1 for the process's first, higher after the device
   * was released and created again; 0 before the first pass). */
  static int GetDeviceUsers();
  vtkTypeInt64 GetDeviceId() const;
  ///@}

  ///@{
  /** Samples per pixel in the current image, the seconds of tracing that produced it, and an
   * estimate of its error: the root mean square over pixels of the standard error of each
   * pixel's mean luminance (linear units; 0 before two samples). */
  int GetAccumulatedSamples() const;
  double GetRenderSeconds() const;
  double GetErrorEstimate() const;
  /** BVH builds (rt backend: volume uploads and visibility changes) and pipeline builds (feature
   * changes) since the device was created: material edits rebuild neither. */
  vtkTypeInt64 GetNumberOfBVHBuilds() const;
  vtkTypeInt64 GetNumberOfPipelineBuilds() const;
  ///@}

protected:
  vtkSegmentationSVDAGRenderer();
  ~vtkSegmentationSVDAGRenderer() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation* request, vtkInformationVector** inputVector,
    vtkInformationVector* outputVector) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
    vtkInformationVector* outputVector) override;

  int Width = 256;
  int Height = 256;
  int PassesPerRender = 1;
  int TraceReduction = 1;
  vtkTypeBool StepStatistics = 0;
  double CameraPosition[3] = { 0, 0, 1 };
  double CameraFocalPoint[3] = { 0, 0, 0 };
  double CameraViewUp[3] = { 0, 1, 0 };
  double CameraViewAngle = 30;
  vtkTypeBool Cropping = 0;
  double CroppingRegionPlanes[6] = { 0.0, 1.0, 0.0, 1.0, 0.0, 1.0 };

private:
  vtkSegmentationSVDAGRenderer(const vtkSegmentationSVDAGRenderer&) = delete;
  void operator=(const vtkSegmentationSVDAGRenderer&) = delete;

  // Sets the camera members to frame the volume (no Modified()); 0 and an error on failure.
  int FrameVolume(vtkSegmentationSVDAG* input, double azimuth, double elevation, double zoom);

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
