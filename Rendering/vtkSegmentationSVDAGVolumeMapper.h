/**
 * @class   vtkSegmentationSVDAGVolumeMapper
 * @brief   path-traces a vtkSegmentationSVDAG inside any VTK OpenGL render window
 *
 * A volume mapper for vtkVolume: its input (SetInputConnection from vtkSegmentationVolumeReader
 * or vtkImageDataToSegmentationSVDAG, or SetInputData) is traced with the Vulkan path tracer
 * (Rendering/core) and drawn into the renderer's viewport:
 *
 * - Camera: rays come from the active camera's world-to-device matrix (vtkOpenGLCamera key
 *   matrices), so perspective and parallel projection, viewports, tiled screenshots
 *   (vtkWindowToImageFilter scale) and the near and far clipping planes are those VTK draws
 *   meshes with. The vtkVolume's matrix (position, orientation, scale, user matrix) applies on
 *   top of the data object's index-to-world transform.
 * - Depth: opaque props drawn before the volume end the rays at their surface (the mapper reads
 *   the depth buffer, resolving MSAA; through memory shared with Vulkan where it can, see
 *   SharedMemory); the volume's first opaque hit is written into the depth
 *   buffer as VTK's window depth (WriteDepth, on by default), so props drawn later, picking and
 *   depth readers see it. Misses are transparent; color is blended with premultiplied alpha.
 *   The settings' Background is not used.
 * - Progressive refinement: while the view, the volume and the settings stay the same, every
 *   render adds Settings->SamplesPerPixel samples per pixel, up to TargetSamplesPerPixel or until
 *   the error estimate falls to ErrorTarget; then renders only composite the finished image.
 *   RenderUntilConverged renders the window until then. GetErrorEstimate is the root mean square,
 *   over pixels, of the standard error of each pixel's mean luminance (linear units).
 * - Time budget (AutoAdjustToRenderTime, on by default): when a full-quality frame would not fit
 *   the time VTK allocates to the volume (vtkRenderWindow::DesiredUpdateRate while interacting),
 *   the frame is traced at a coarser LOD and/or a reduced resolution (svdag::render::FrameBudget),
 *   one sample per pixel; still renders (StillUpdateRate) return to full quality.
 * - Appearance per ORIGINAL label value: vtkSegmentationSVDAGLabelProperties (colors, lookup
 *   table, opacity, visibility, materials). Material edits re-upload a buffer; visibility edits
 *   rebuild only the acceleration structure.
 * - Picking: Pick(renderer, x, y) reads the label, position and normal under a display pixel
 *   from the last frame traced for that renderer.
 * - Selection: VTK's own pickers see the volume. During a vtkHardwareSelector render (which
 *   vtkPropPicker, vtkRenderer::PickProp and area selections use) the mapper draws, where the
 *   volume is hit and not farther than what the depth buffer holds, the selector's ids instead
 *   of the shaded image, and writes the hit's depth: the prop (and process) color, as
 *   COMPOSITE_INDEX the hit label's index in the volume's label table + 1 (1 .. 0xfffffe; later
 *   indices all give 0xffffff), and as the point or cell id of either field association the hit
 *   voxel's index i + nx (j + ny k), the input image's point id (at LOD voxel the voxel hit; at
 *   coarser LODs the voxel where the ray enters the block or leaf box). The hits are those of
 *   the full-quality frame; the last traced image is used when the view and what is drawn
 *   before the volume are the same (else one pass is traced and refinement goes on from it), so
 *   picking does not disturb what the next render shows. The label is one call away:
 *
 *     picker->PickProp(x, y, renderer);                  // vtkPropPicker
 *     if (picker->GetViewProp() == volume && mapper->Pick(renderer, x, y))
 *       label = mapper->GetPickedLabel();                // (x, y): the pixel's center
 *     // vtkHardwareSelector: one node per label, PROP() == volume:
 *     label = mapper->GetLabelForCompositeIndex(node->GetProperties()->Get(
 *       vtkSelectionNode::COMPOSITE_INDEX()));
 *
 *   vtkPropPicker's GetPickPosition (vtkWorldPointPicker reading the depth buffer) is the hit
 *   point to the depth buffer's precision. Pickers that intersect a prop's vtkDataSet
 *   (vtkCellPicker, vtkPointPicker, vtkVolumePicker) cannot see the compressed input.
 *
 * Errors (no usable Vulkan device: the message names every device found and what it lacks; the
 * rt backend on a device without ray tracing; a render window that is not OpenGL) are reported with vtkErrorMacro, and the volume is
 * not drawn.
 */
#ifndef vtkSegmentationSVDAGVolumeMapper_h
#define vtkSegmentationSVDAGVolumeMapper_h

#include "vtkAbstractVolumeMapper.h"
#include "vtkSVDAGRenderingModule.h" // for export macro

#include <memory> // for std::unique_ptr

class vtkRenderWindow;
class vtkSegmentationSVDAG;
class vtkSegmentationSVDAGLabelProperties;
class vtkSegmentationSVDAGRenderSettings;

class VTKSVDAGRENDERING_EXPORT vtkSegmentationSVDAGVolumeMapper : public vtkAbstractVolumeMapper
{
public:
  static vtkSegmentationSVDAGVolumeMapper* New();
  vtkTypeMacro(vtkSegmentationSVDAGVolumeMapper, vtkAbstractVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  vtkMTimeType GetMTime() override;

  ///@{
  /** The volume to render (or SetInputConnection). */
  void SetInputData(vtkSegmentationSVDAG* input);
  vtkSegmentationSVDAG* GetInput();
  ///@}

  ///@{
  /** The path tracer's settings (LOD, samples, bounces, lighting, exposure): never null. */
  vtkSegmentationSVDAGRenderSettings* GetSettings();
  void SetSettings(vtkSegmentationSVDAGRenderSettings* settings);
  /** Per-label appearance by original label value: never null. */
  vtkSegmentationSVDAGLabelProperties* GetLabelProperties();
  void SetLabelProperties(vtkSegmentationSVDAGLabelProperties* properties);
  ///@}

  ///@{
  /** Write the volume's first opaque hit into the depth buffer (default on). */
  vtkSetMacro(WriteDepth, bool);
  vtkGetMacro(WriteDepth, bool);
  vtkBooleanMacro(WriteDepth, bool);
  /** Trace coarser and smaller images when a full frame would exceed the allocated render time
   * (default on). */
  vtkSetMacro(AutoAdjustToRenderTime, bool);
  vtkGetMacro(AutoAdjustToRenderTime, bool);
  vtkBooleanMacro(AutoAdjustToRenderTime, bool);
  /** Samples per pixel at which a still view stops refining (default 64). */
  vtkSetClampMacro(TargetSamplesPerPixel, int, 1, 1 << 24);
  vtkGetMacro(TargetSamplesPerPixel, int);
  /** Error estimate at which a still view stops refining (default 0: refine to
   * TargetSamplesPerPixel). */
  vtkSetClampMacro(ErrorTarget, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(ErrorTarget, double);
  /** Refine a still render to the targets within that render (default off: each render adds one
   * pass, and the application's timer or RenderUntilConverged refines, so that a window stays
   * responsive). With it on, every still render (the window's DesiredUpdateRate at or below its
   * interactor's StillUpdateRate, or 0.0001 without an interactor) returns the refined image, so
   * what vtkWindowToImageFilter, vtkRegressionTestImage or a screenshot captures is refined;
   * interactive renders still keep to their time. For off-screen windows and batch captures
   * (vtksvdag.add_segmentation turns it on for off-screen plotters). A tile of a tiled capture
   * (a vtkWindowToImageFilter scale above 1) is always refined within its render. */
  vtkSetMacro(RefineStillRenders, bool);
  vtkGetMacro(RefineStillRenders, bool);
  vtkBooleanMacro(RefineStillRenders, bool);
  /** Seconds a still render refines at most with RefineStillRenders (default 60). */
  vtkSetClampMacro(RefineTimeLimit, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(RefineTimeLimit, double);
  /** While the path tracer's pipeline compiles (the first frames of a process with empty shader
   * caches, or a feature switched on), draw the block boxes' first hits under a headlight from
   * a small pipeline and compile the full one in the background (default on), so that the
   * window never waits; a one-shot timer of the window's interactor renders again until the
   * full pipeline is ready. Only in a window whose interactor is initialized (someone looks at
   * it) and never for a render that must be final (RefineStillRenders' still renders, tiles,
   * selections): those wait for the full pipeline. GetLastFramePreviewed(): whether the last
   * frame was such a preview. */
  vtkSetMacro(PreviewWhileCompiling, bool);
  vtkGetMacro(PreviewWhileCompiling, bool);
  vtkBooleanMacro(PreviewWhileCompiling, bool);
  bool GetLastFramePreviewed();
  ///@}

  ///@{
  /**
   * Cropping, with vtkVolumeMapper's names and meaning for its simple case (keep the central
   * box, VTK_CROP_SUBVOLUME): while Cropping is on (default off) only what lies inside
   * CroppingRegionPlanes (xmin, xmax, ymin, ymax, zmin, zmax) is drawn. The planes are in the
   * data's world coordinates (origin, spacing and direction applied, before the vtkVolume's
   * matrix), like vtkVolumeMapper's. Cut voxels show their cut faces, as with clipping planes.
   * An inverted (min > max) or non-finite box is an error and keeps the previous one.
   *
   * Clipping planes: vtkAbstractMapper's (AddClippingPlane, SetClippingPlanes,
   * RemoveAllClippingPlanes), in VTK's world coordinates (after the vtkVolume's matrix, like
   * vtkGPUVolumeRayCastMapper's), each keeping the side its vtkPlane normal points to, at most
   * GetMaximumNumberOfClippingPlanes() (6). The mapper owns them (the settings hold none), like
   * vtkSegmentationSVDAGRenderer, which has the same names. Every ray is clipped (cut-away parts cast no
   * shadow) and a cut through a label shows its cut face with the plane's normal (at block and
   * leaf LOD the cross-section of the block or leaf box). Bad planes (more than 6, a zero or
   * non-finite normal) are reported by Render with vtkErrorMacro and nothing is drawn. A change
   * of planes or cropping restarts the refinement but does not rebuild the BVH.
   */
  vtkSetMacro(Cropping, vtkTypeBool);
  vtkGetMacro(Cropping, vtkTypeBool);
  vtkBooleanMacro(Cropping, vtkTypeBool);
  void SetCroppingRegionPlanes(
    double xmin, double xmax, double ymin, double ymax, double zmin, double zmax);
  void SetCroppingRegionPlanes(const double planes[6])
  {
    this->SetCroppingRegionPlanes(planes[0], planes[1], planes[2], planes[3], planes[4], planes[5]);
  }
  vtkGetVector6Macro(CroppingRegionPlanes, double);
  static int GetMaximumNumberOfClippingPlanes();
  ///@}

  /** Creates the Vulkan renderer now (else on the first render): returns false and reports the
   * reason (no usable device: every device found and what it lacks) with
   * vtkErrorMacro. It also starts compiling, on a thread of its own, the pipelines that the
   * current settings' first frame needs, so that a caller that sets the settings, calls this and
   * then reads its volume has them compiled meanwhile (the compilation is most of a first
   * image's wait on a CPU driver with empty caches). */
  bool InitializeDevice();

  /** Renders the window until the view has converged (TargetSamplesPerPixel or ErrorTarget) or
   * `maximumSeconds` have passed; returns the number of renders (0 on error). */
  int RenderUntilConverged(vtkRenderWindow* window, double maximumSeconds = 60.0);
  /** Whether the last frame was full quality and refined to the targets. */
  bool IsConverged();

  ///@{
  /** The last frame: samples per pixel accumulated, error estimate, seconds of tracing, the LOD
   * and reduction factor it was traced at, its trace and total milliseconds. */
  int GetAccumulatedSamples();
  double GetErrorEstimate();
  double GetRenderSeconds();
  int GetLastLOD();
  int GetLastReductionFactor();
  double GetLastTraceMilliseconds();
  double GetLastFrameMilliseconds();
  /** The Vulkan device ("" before the first render). */
  const char* GetDeviceName();
  /** BVH builds since the device was created (visibility edits rebuild, material edits not). */
  vtkTypeInt64 GetNumberOfBVHBuilds();
  ///@}

  ///@{
  /**
   * How the traced color and the depth move between OpenGL and Vulkan. With SharedMemory on
   * (default), where the Vulkan device exports memory that the window's OpenGL imports
   * (VK_KHR_external_memory_fd and GL_EXT_memory_object_fd on the same device and driver, by
   * their UUIDs: Mesa's lavapipe with llvmpipe, or one GPU's Vulkan and OpenGL drivers), the
   * compositor reads the color straight from the renderer's output buffer; otherwise (or with
   * SharedMemory off) it is read back to the host and uploaded. The depth likewise, where the
   * device also computes in double precision (shaderFloat64) and SharedDepth is on (default):
   * OpenGL reads the scene's depth (what was drawn before the volume) into a host-visible buffer
   * of the device (glReadPixels into a pixel pack buffer on the imported memory, two buffers in
   * turn so that a frame's depth can be compared with the accumulating one's in place), a
   * compute pass turns it into the rays' limits before the trace and composites the depth to
   * write from the traced hits after it, and OpenGL uploads that into its depth texture from
   * the imported memory (a pixel unpack buffer); otherwise the mapper computes both on the host
   * from a host copy of the depth. Every path draws the same pixels and writes the same depth,
   * bit for bit (the compute pass repeats the host's double-precision arithmetic, operation by
   * operation). Neither driver shares semaphores: OpenGL's side is waited for with fences.
   * GetCompositePath: the last frame's color path, GetDepthPath its depth path, each "shared
   * memory" or "host" ("" before a frame; an import that fails is reported once as a warning and
   * the host path is used from then on). GetLastCopyMilliseconds: the part of the last frame
   * spent moving depth and image between OpenGL, the host and Vulkan (scene depth read, and on
   * the host path turned into ray limits; outputs read back; depth composited; depth and color
   * uploaded or imported and drawn); on the shared depth path the ray limits are computed in the
   * trace's submission and count as trace time.
   */
  vtkSetMacro(SharedMemory, bool);
  vtkGetMacro(SharedMemory, bool);
  vtkBooleanMacro(SharedMemory, bool);
  vtkSetMacro(SharedDepth, bool);
  vtkGetMacro(SharedDepth, bool);
  vtkBooleanMacro(SharedDepth, bool);
  const char* GetCompositePath();
  const char* GetDepthPath();
  double GetLastCopyMilliseconds();
  ///@}

  ///@{
  /** The backend in use, "rt" or "compute" ("" before the first pass, or where Settings asks for
   * one the device cannot run), and the bytes of device memory held, in all (GetDeviceBytes) and
   * by part: the volume's encoding (block and DAG streams), what the backend finds blocks with
   * (BLAS, TLAS and the primitive map; or the compute backend's cell grid and hidden-label bits),
   * per-label materials and environment tables, and the images (outputs, accumulation, ray
   * limits); 0 before the first pass. */
  const char* GetBackendInUse();
  vtkTypeInt64 GetDeviceBytes();
  vtkTypeInt64 GetEncodingBytes();
  vtkTypeInt64 GetAccelerationBytes();
  vtkTypeInt64 GetMaterialBytes();
  vtkTypeInt64 GetImageBytes();
  ///@}

  ///@{
  /** Every mapper and renderer of a process shares one Vulkan device (created on first use,
   * released with its last user). GetDeviceUsers: how many use it now (0: none exists);
   * GetDeviceId: which device this one uses (1 for the process's first, higher after the device
   * was released and created again; 0 before the first pass). */
  static int GetDeviceUsers();
  vtkTypeInt64 GetDeviceId();
  ///@}

  ///@{
  /**
   * The label under display pixel (x, y) (pixels, origin at the bottom left, as VTK's display
   * coordinates) in the last frame traced for `renderer`. Returns true on a hit; then
   * GetPickedLabel (the original value; a uint64 label >= 2^63 as the int64 with its bits),
   * GetPickedPosition (world) and GetPickedNormal (world, unit; zero where the camera is inside
   * the label) describe it, and GetPickedShadingNormal the normal the frame was shaded with
   * (world, unit: the face's, or the smooth estimate with Settings Shading smooth). False on
   * background, outside the viewport or before a frame.
   */
  bool Pick(vtkRenderer* renderer, double x, double y);
  /** The original label value (as GetPickedLabel's) that a selection node's COMPOSITE_INDEX
   * names (see Selection above): index i is the i-th label of the volume's label table,
   * counting from 1. Reports an error and returns 0 for an index outside 1 .. labels (or no
   * input). */
  vtkTypeInt64 GetLabelForCompositeIndex(unsigned int compositeIndex);
  vtkTypeInt64 GetPickedLabel();
  void GetPickedPosition(double position[3]);
  void GetPickedNormal(double normal[3]);
  void GetPickedShadingNormal(double normal[3]);
  ///@}

  /** World bounds of the volume's voxels (before the vtkVolume's matrix). */
  double* GetBounds() VTK_SIZEHINT(6) override;
  using Superclass::GetBounds;

  void Render(vtkRenderer* renderer, vtkVolume* volume) override;
  void ReleaseGraphicsResources(vtkWindow* window) override;

protected:
  vtkSegmentationSVDAGVolumeMapper();
  ~vtkSegmentationSVDAGVolumeMapper() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

  bool WriteDepth = true;
  bool SharedMemory = true;
  bool SharedDepth = true;
  bool AutoAdjustToRenderTime = true;
  int TargetSamplesPerPixel = 64;
  double ErrorTarget = 0.0;
  bool RefineStillRenders = false;
  double RefineTimeLimit = 60.0;
  bool PreviewWhileCompiling = true;
  vtkTypeBool Cropping = 0;
  double CroppingRegionPlanes[6] = { 0.0, 1.0, 0.0, 1.0, 0.0, 1.0 };

private:
  vtkSegmentationSVDAGVolumeMapper(const vtkSegmentationSVDAGVolumeMapper&) = delete;
  void operator=(const vtkSegmentationSVDAGVolumeMapper&) = delete;

  // InitializeDevice without compiling ahead: what every render does first.
  bool CreateRenderer();

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
