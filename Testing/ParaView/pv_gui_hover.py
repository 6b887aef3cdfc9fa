"""paraview (GUI) side of test_paraview.py's GUI test, run in the GUI's Python shell once the
QtTesting script has loaded the plugin through the Plugin Manager: opens the volume with the
plugin's reader and shows it in a view of a fixed size (the layout's preview mode) and camera,
before the QtTesting script moves the mouse. The scene comes from the JSON file named by
VTKSVDAG_GUI_SCENE: file, name, size, camera, out (where the QtTesting script finally writes
the view's size and camera as they were then).
"""
import json
import os

from paraview.simple import (GetActiveViewOrCreate, GetLayout, Render,
                             SegmentationVolumeReader, Show)

with open(os.environ["VTKSVDAG_GUI_SCENE"]) as f:
    scene = json.load(f)

reader = SegmentationVolumeReader(registrationName=scene["name"], FileName=scene["file"])
view = GetActiveViewOrCreate("RenderView")
GetLayout(view).PreviewMode = scene["size"]
view.OrientationAxesVisibility = 0
display = Show(reader, view)
display.MaximumBounces = 0
# paraview.simple resets the camera on a view's first render: the camera is set after it.
Render(view)
camera = scene["camera"]
view.CameraPosition = camera["position"]
view.CameraFocalPoint = camera["focal_point"]
view.CameraViewUp = camera["view_up"]
view.CameraViewAngle = camera["view_angle"]
view.CameraParallelProjection = 0
Render(view)


