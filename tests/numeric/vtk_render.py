# Renders a scene with VTK's vtkFixedPointVolumeRayCastMapper (CPU; independent of peakcast), shading off.
# Usage: vtk_render.py SCENE.json OUT.png   (the scene's volume must be a MetaImage file)
import json, sys
import vtk
scene = json.load(open(sys.argv[1])); out = sys.argv[2]
r = vtk.vtkNrrdReader() if scene["volume"].endswith(("nrrd", "nhdr")) else vtk.vtkMetaImageReader()
r.SetFileName(scene["volume"]); r.Update()
img = r.GetOutput()
ctf = vtk.vtkColorTransferFunction(); otf = vtk.vtkPiecewiseFunction()
for v, cr, cg, cb, a in scene["tf"]["points"]:
    ctf.AddRGBPoint(v, cr, cg, cb); otf.AddPoint(v, a)
prop = vtk.vtkVolumeProperty(); prop.SetColor(ctf); prop.SetScalarOpacity(otf)
prop.SetInterpolationTypeToLinear(); prop.ShadeOff()
prop.SetScalarOpacityUnitDistance(scene["tf"].get("opacity_unit", min(img.GetSpacing())))
mapper = vtk.vtkFixedPointVolumeRayCastMapper(); mapper.SetInputData(img)
mapper.SetSampleDistance(scene["render"]["step"]); mapper.SetAutoAdjustSampleDistances(0)
vol = vtk.vtkVolume(); vol.SetMapper(mapper); vol.SetProperty(prop)
ren = vtk.vtkRenderer(); ren.AddVolume(vol); ren.SetBackground(*scene.get("background", [0, 0, 0]))
cam = ren.GetActiveCamera(); c = scene["camera"]
cam.SetPosition(*c["eye"]); cam.SetFocalPoint(*c["center"]); cam.SetViewUp(*c["up"]); cam.SetViewAngle(c.get("fov_y", 30))
if c.get("projection") == "orthographic":
    cam.ParallelProjectionOn(); cam.SetParallelScale(c["height"] / 2)
ren.ResetCameraClippingRange()
win = vtk.vtkRenderWindow(); win.SetOffScreenRendering(1); win.AddRenderer(ren)
win.SetSize(scene["image"]["width"], scene["image"]["height"]); win.Render()
w2i = vtk.vtkWindowToImageFilter(); w2i.SetInput(win); w2i.ReadFrontBufferOff(); w2i.Update()
wr = vtk.vtkPNGWriter(); wr.SetFileName(out); wr.SetInputConnection(w2i.GetOutputPort()); wr.Write()
print("vtk", vtk.vtkVersion.GetVTKVersion(), "wrote", out)
