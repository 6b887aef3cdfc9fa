/**
 * @class   vtkSegmentationSVDAGLabelProperties
 * @brief   per-label appearance of a segmentation, keyed by the ORIGINAL label values
 *
 * What each label looks like in the volume mapper: color, opacity, visibility and the path
 * tracer's material (roughness, metallic, transmission, index of refraction, specular, emission).
 * Labels are named by their value in the segmentation (not by their index in the compressed
 * label table), so the same object applies to any volume with those labels. A value a volume
 * does not hold is ignored. Values are 64-bit: a uint64 label of 2^63 or more is named by the
 * int64 with the same bits.
 *
 * Colors are display (sRGB) values in [0, 1], as everywhere in VTK; the path tracer works in
 * linear RGB and converts them. Colors come, in order of precedence, from SetColor, from the
 * LookupTable (any vtkScalarsToColors: a vtkLookupTable with indexed or interval lookup, a
 * vtkColorTransferFunction, mapped at the label value), else from a hash of the label's index.
 *
 * Opacity 0 hides a label (like SetVisibility(false)); 0 < opacity < 1 is rendered as the path
 * tracer's transmission, an approximation of alpha blending: the label's surface passes
 * 1 - opacity of the light straight through, tinted by its color, with no reflection at the
 * surface (index of refraction 1), and continues to what lies behind. The effective transmission
 * is 1 - opacity * (1 - Transmission).
 *
 * Defaults (labels never set): opacity 1, visible, roughness 0.6, metallic 0, transmission 0,
 * IOR 1.5, specular 0.5, no emission (svdag::render::Renderer::defaultMaterial).
 *
 * Selection highlight: highlighted labels (AddHighlightedLabel) add HighlightColor (display sRGB,
 * converted to linear) times HighlightIntensity to their emission, an emissive tint that shows
 * under any lighting. While at least one label is highlighted, every other label's base color is
 * multiplied by DimOthers (1: unchanged, 0.3: 30 % of its albedo) and its opacity by
 * OthersOpacity (below 1: see-through, as SetOpacity). A highlight change is a material upload
 * that restarts the accumulation; it does not rebuild the acceleration structure (OthersOpacity 0
 * would hide the others, which does). The first emissive or transmissive material in a scene
 * recompiles the path tracer's pipeline once (its specialization constants), not the BVH.
 *
 * A mapper re-uploads the materials (a buffer copy) when the MTime changes; only a change of
 * which labels are visible rebuilds its acceleration structure.
 */
#ifndef vtkSegmentationSVDAGLabelProperties_h
#define vtkSegmentationSVDAGLabelProperties_h

#include "vtkObject.h"
#include "vtkSVDAGRenderingModule.h" // for export macro

#include <memory> // for std::unique_ptr
#include <vector> // for std::vector

class vtkScalarsToColors;
class vtkSegmentationSVDAG;
#ifndef __VTK_WRAP__
namespace svdag
{
class Volume;
namespace shading
{
struct Material;
}
}
#endif

class VTKSVDAGRENDERING_EXPORT vtkSegmentationSVDAGLabelProperties : public vtkObject
{
public:
  static vtkSegmentationSVDAGLabelProperties* New();
  vtkTypeMacro(vtkSegmentationSVDAGLabelProperties, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  vtkMTimeType GetMTime() override;

  ///@{
  /** The appearance of one label value. Values are clamped: colors and emission to >= 0 (colors
   * to [0, 1]), opacity, roughness, metallic, transmission and specular to [0, 1], IOR to
   * [1e-3, 10]. The getters return the defaults for labels never set. */
  void SetColor(vtkTypeInt64 label, double r, double g, double b);
  /** Whether a color was set for the label; GetColor returns it (else false, rgb untouched). */
  bool GetColor(vtkTypeInt64 label, double rgb[3]);
  /** The color set for the label (3 values, valid until the next call), or nullptr (None in
   * Python) when none was set. The form wrappers can return: `props.GetColor(17)` in Python. */
  double* GetColor(vtkTypeInt64 label) VTK_SIZEHINT(3);
  /** The display (sRGB) color `label` is drawn with in `volume`: SetColor's, else the lookup
   * table's, else the default color of its label index; before the highlight's dimming. False
   * (rgb untouched) when the volume does not hold the label. What legends and label tables
   * show. */
  bool GetDisplayColor(vtkSegmentationSVDAG* volume, vtkTypeInt64 label, double rgb[3]);
  /** The default color (display sRGB) of the label at `labelIndex` in its volume's table (the
   * labels sorted by value): what a label without SetColor or lookup table is drawn with. A
   * volume split into pieces colors each piece's labels by their indices in the whole table. */
  static void GetDefaultColor(vtkIdType labelIndex, double rgb[3]);
  /** Forgets the label's color only: the lookup table or the hash colors it again. */
  void RemoveColor(vtkTypeInt64 label);
  void SetOpacity(vtkTypeInt64 label, double opacity);
  double GetOpacity(vtkTypeInt64 label);
  void SetVisibility(vtkTypeInt64 label, bool visible);
  bool GetVisibility(vtkTypeInt64 label);
  void SetRoughness(vtkTypeInt64 label, double roughness);
  double GetRoughness(vtkTypeInt64 label);
  void SetMetallic(vtkTypeInt64 label, double metallic);
  double GetMetallic(vtkTypeInt64 label);
  void SetTransmission(vtkTypeInt64 label, double transmission);
  double GetTransmission(vtkTypeInt64 label);
  void SetIOR(vtkTypeInt64 label, double ior);
  double GetIOR(vtkTypeInt64 label);
  void SetSpecular(vtkTypeInt64 label, double specular);
  double GetSpecular(vtkTypeInt64 label);
  /** Emitted linear radiance (>= 0). */
  void SetEmission(vtkTypeInt64 label, double r, double g, double b);
  /** Whether an emission was set for the label; GetEmission returns it (else false, rgb
   * untouched). The highlight's tint is not included (GetMaterial has it). */
  bool GetEmission(vtkTypeInt64 label, double rgb[3]);
  ///@}

  ///@{
  /** The selection highlight (see the class description). Highlighting a label the volume does
   * not hold is allowed (it is ignored there, as every setting is). */
  void AddHighlightedLabel(vtkTypeInt64 label);
  void RemoveHighlightedLabel(vtkTypeInt64 label);
  void RemoveAllHighlightedLabels();
  bool IsHighlighted(vtkTypeInt64 label);
  /** Highlighted labels, in ascending order. */
  vtkIdType GetNumberOfHighlightedLabels();
  vtkTypeInt64 GetHighlightedLabel(vtkIdType i);
  /** The tint's color, display sRGB in [0, 1] (default 1, 0.8, 0.2: amber). */
  void SetHighlightColor(double r, double g, double b);
  void SetHighlightColor(const double rgb[3]) { this->SetHighlightColor(rgb[0], rgb[1], rgb[2]); }
  vtkGetVector3Macro(HighlightColor, double);
  /** The tint's radiance scale, >= 0 (default 1: about as bright as a white surface under the
   * default unit environment). */
  vtkSetClampMacro(HighlightIntensity, double, 0.0, 1e6);
  vtkGetMacro(HighlightIntensity, double);
  /** Base color factor of the labels not highlighted while a highlight is active, in [0, 1]
   * (default 1: no dimming). */
  vtkSetClampMacro(DimOthers, double, 0.0, 1.0);
  vtkGetMacro(DimOthers, double);
  /** Opacity factor of the labels not highlighted while a highlight is active, in [0, 1]
   * (default 1; 0 hides them, which rebuilds the acceleration structure). */
  vtkSetClampMacro(OthersOpacity, double, 0.0, 1.0);
  vtkGetMacro(OthersOpacity, double);
  ///@}

  /**
   * The material the renderer gets for `label` in `volume`, everything above applied (colors,
   * table, highlight, opacity): 16 values, linear base color rgb, visibility (0 or 1), emission
   * rgb, 0, roughness, metallic, transmission, IOR, specular, 0, 0, 0. Returns false (material
   * untouched) when the volume does not hold the label.
   */
  bool GetMaterial(vtkSegmentationSVDAG* volume, vtkTypeInt64 label, double material[16]);

  ///@{
  /** Colors of labels without SetColor: the table's color at the label value. */
  void SetLookupTable(vtkScalarsToColors* table);
  vtkScalarsToColors* GetLookupTable();
  ///@}

  ///@{
  /** Hide (show) every label, those never set included; SetVisibility(label, true) after
   * HideAllLabels shows only that label. Opacity is kept. */
  void HideAllLabels();
  void ShowAllLabels();
  /** Forgets everything set for one label, or for all (the table stays). */
  void RemoveLabel(vtkTypeInt64 label);
  void RemoveAllLabels();
  /** Labels with something set, in ascending order. */
  vtkIdType GetNumberOfLabels();
  vtkTypeInt64 GetLabel(vtkIdType i);
  ///@}

#ifndef __VTK_WRAP__
  /** The materials of a volume's labels, by label index (the core renderer's layout). */
  std::vector<svdag::shading::Material> MaterialsFor(const svdag::Volume& volume);
#endif

protected:
  vtkSegmentationSVDAGLabelProperties();
  ~vtkSegmentationSVDAGLabelProperties() override;

  double HighlightColor[3] = { 1.0, 0.8, 0.2 };
  double HighlightIntensity = 1.0;
  double DimOthers = 1.0;
  double OthersOpacity = 1.0;
  double ColorReturned[3] = { 0.0, 0.0, 0.0 }; // what GetColor(label) points to

private:
  vtkSegmentationSVDAGLabelProperties(const vtkSegmentationSVDAGLabelProperties&) = delete;
  void operator=(const vtkSegmentationSVDAGLabelProperties&) = delete;

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
