#include "pqSegmentationLabelReadout.h"

#include "pqApplicationCore.h"
#include "pqCoreUtilities.h"
#include "pqDataRepresentation.h"
#include "pqPipelineSource.h"
#include "pqRenderView.h"
#include "pqServerManagerModel.h"

#include "vtkCommand.h"
#include "vtkEventQtSlotConnect.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"
#include "vtkSMRenderViewProxy.h"
#include "vtkSMSessionProxyManager.h"

#include <QCursor>
#include <QLabel>
#include <QMainWindow>
#include <QStatusBar>
#include <QToolTip>

#include <cstring>

namespace
{
// The proxy name of the representation in vtkSVDAG.xml.
const char* const RepresentationProxyName = "SegmentationPathTracingRepresentation";
// How long the pointer rests before a pick: moving across a view costs no server round trips.
constexpr int RestMilliseconds = 150;
}

pqSegmentationLabelReadout::pqSegmentationLabelReadout(QObject* parent)
  : QObject(parent)
{
  this->Rest.setSingleShot(true);
  this->Rest.setInterval(RestMilliseconds);
  QObject::connect(&this->Rest, &QTimer::timeout, this, &pqSegmentationLabelReadout::pickUnderPointer);
}

pqSegmentationLabelReadout::~pqSegmentationLabelReadout()
{
  this->onShutdown();
}

void pqSegmentationLabelReadout::onStartup()
{
  pqServerManagerModel* model = pqApplicationCore::instance()->getServerManagerModel();
  QObject::connect(model, &pqServerManagerModel::viewAdded, this, &pqSegmentationLabelReadout::watch);
  QObject::connect(
    model, &pqServerManagerModel::preViewRemoved, this, &pqSegmentationLabelReadout::forgetView);
  QObject::connect(model, &pqServerManagerModel::preRepresentationRemoved, this,
    &pqSegmentationLabelReadout::forgetRepresentation);
  for (pqView* view : model->findItems<pqView*>())
  {
    this->watch(view);
  }
}

void pqSegmentationLabelReadout::onShutdown()
{
  this->Rest.stop();
  this->Connections->Disconnect();
  this->Interactors.clear();
  this->Pickers.clear();
  if (pqApplicationCore* core = pqApplicationCore::instance())
  {
    QObject::disconnect(core->getServerManagerModel(), nullptr, this, nullptr);
  }
  delete this->StatusLabel;
}

void pqSegmentationLabelReadout::watch(pqView* view)
{
  if (auto* renderView = qobject_cast<pqRenderView*>(view))
  {
    // A view that has rendered has its widget and interactor; attaching is idempotent.
    QObject::connect(renderView, &pqView::endRender, this,
      [this, renderView]() { this->attach(renderView); });
  }
}

void pqSegmentationLabelReadout::attach(pqRenderView* view)
{
  vtkRenderWindowInteractor* interactor = view->getRenderViewProxy()->GetInteractor();
  if (!interactor || this->Interactors.contains(interactor))
  {
    return;
  }
  this->Interactors.insert(interactor, view);
  this->Connections->Connect(
    interactor, vtkCommand::MouseMoveEvent, this, SLOT(pointerMoved(vtkObject*)));
  this->Connections->Connect(interactor, vtkCommand::LeaveEvent, this, SLOT(pointerLeft()));
}

void pqSegmentationLabelReadout::forgetView(pqView* view)
{
  for (auto it = this->Interactors.begin(); it != this->Interactors.end();)
  {
    if (it.value() == view || it.value().isNull())
    {
      this->Connections->Disconnect(it.key());
      it = this->Interactors.erase(it);
    }
    else
    {
      ++it;
    }
  }
  if (this->Hovered == view)
  {
    this->pointerLeft();
  }
}

void pqSegmentationLabelReadout::forgetRepresentation(pqRepresentation* representation)
{
  this->Pickers.remove(representation);
}

void pqSegmentationLabelReadout::pointerMoved(vtkObject* object)
{
  auto* interactor = vtkRenderWindowInteractor::SafeDownCast(object);
  this->Hovered = this->Interactors.value(object);
  if (!interactor || !this->Hovered)
  {
    return;
  }
  // Display pixels, origin bottom left: what the picker takes.
  interactor->GetEventPosition(this->Pointer);
  this->Rest.start();
}

void pqSegmentationLabelReadout::pointerLeft()
{
  this->Rest.stop();
  this->Hovered = nullptr;
  this->show(QString());
}

void pqSegmentationLabelReadout::pickUnderPointer()
{
  pqRenderView* view = this->Hovered;
  if (!view)
  {
    return;
  }
  const double pixel[2] = { static_cast<double>(this->Pointer[0]),
    static_cast<double>(this->Pointer[1]) };
  for (pqRepresentation* representation : view->getRepresentations())
  {
    auto* data = qobject_cast<pqDataRepresentation*>(representation);
    if (!data || !data->isVisible() ||
      std::strcmp(data->getProxy()->GetXMLName(), RepresentationProxyName) != 0)
    {
      continue;
    }
    vtkSMProxy* picker = this->pickerFor(data);
    vtkSMPropertyHelper(picker, "PickPixel").Set(pixel, 2);
    // Pushed even when the pixel is the last one: the frame under it may have changed.
    picker->UpdateProperty("PickPixel", 1);
    picker->UpdatePropertyInformation();
    if (vtkSMPropertyHelper(picker, "PickedHit").GetAsInt())
    {
      const vtkIdType label = vtkSMPropertyHelper(picker, "PickedLabel").GetAsIdType();
      pqPipelineSource* source = data->getInput();
      this->show(QString("Label %1 (%2)")
                   .arg(static_cast<qlonglong>(label))
                   .arg(source ? source->getSMName() : QString()));
      return;
    }
  }
  this->show(QString());
}

vtkSMProxy* pqSegmentationLabelReadout::pickerFor(pqDataRepresentation* representation)
{
  vtkSmartPointer<vtkSMProxy>& picker = this->Pickers[representation];
  if (!picker)
  {
    picker.TakeReference(representation->proxyManager()->NewProxy("misc", "SegmentationPicker"));
    vtkSMPropertyHelper(picker, "Representation").Set(representation->getProxy());
    picker->UpdateVTKObjects();
  }
  return picker;
}

void pqSegmentationLabelReadout::show(const QString& text)
{
  if (!this->StatusLabel)
  {
    auto* window = qobject_cast<QMainWindow*>(pqCoreUtilities::mainWidget());
    if (!window)
    {
      return;
    }
    this->StatusLabel = new QLabel(window->statusBar());
    this->StatusLabel->setObjectName("SegmentationLabelReadout");
    this->StatusLabel->setToolTip("Segmentation label under the mouse pointer (vtkSVDAG)");
    window->statusBar()->addPermanentWidget(this->StatusLabel);
  }
  this->StatusLabel->setText(text);
  if (text.isEmpty())
  {
    QToolTip::hideText();
  }
  else if (this->Hovered)
  {
    QToolTip::showText(QCursor::pos(), text, this->Hovered->widget());
  }
}
