/**
 * @class   pqSegmentationLabelReadout
 * @brief   The GUI's hover read-out: the label under the mouse pointer in a render view
 *
 * When the pointer rests on a render view (150 ms without moving), the visible 'Segmentation
 * Path Tracing' representations of that view are picked there, in their order in the view,
 * through the render-server proxy misc/SegmentationPicker (so the pick runs where the frame was
 * traced, in built-in and client-server sessions alike). The first hit is shown as
 * "Label <value> (<source>)" in a tooltip and in the status bar's permanent label
 * SegmentationLabelReadout; a miss, or the pointer leaving the view, clears it. The vtkSVDAG
 * plugin registers this class as an auto-start interface, so it runs as soon as the plugin is
 * loaded into the GUI (PV_PLUGIN_PATH or the Plugin Manager).
 */
#ifndef pqSegmentationLabelReadout_h
#define pqSegmentationLabelReadout_h

#include <QMap>
#include <QObject>
#include <QPointer>
#include <QTimer>

#include "vtkNew.h"
#include "vtkSmartPointer.h"

class QLabel;
class pqDataRepresentation;
class pqRenderView;
class pqRepresentation;
class pqView;
class vtkEventQtSlotConnect;
class vtkObject;
class vtkSMProxy;

class pqSegmentationLabelReadout : public QObject
{
  Q_OBJECT

public:
  explicit pqSegmentationLabelReadout(QObject* parent = nullptr);
  ~pqSegmentationLabelReadout() override;

  void onStartup();
  void onShutdown();

private Q_SLOTS:
  void watch(pqView* view);
  void forgetView(pqView* view);
  void forgetRepresentation(pqRepresentation* representation);
  void pointerMoved(vtkObject* interactor);
  void pointerLeft();
  void pickUnderPointer();

private:
  Q_DISABLE_COPY(pqSegmentationLabelReadout)

  // Attaches to the view's interactor, which exists once the view has its widget.
  void attach(pqRenderView* view);
  vtkSMProxy* pickerFor(pqDataRepresentation* representation);
  void show(const QString& text);

  vtkNew<vtkEventQtSlotConnect> Connections;
  // Interactor -> its view, for the view a VTK event came from.
  QMap<vtkObject*, QPointer<pqRenderView>> Interactors;
  // One picker per representation; dropped with the representation (it holds a reference).
  QMap<pqRepresentation*, vtkSmartPointer<vtkSMProxy>> Pickers;
  QPointer<pqRenderView> Hovered;
  int Pointer[2] = { 0, 0 };
  QTimer Rest;
  QPointer<QLabel> StatusLabel;
};

#endif
