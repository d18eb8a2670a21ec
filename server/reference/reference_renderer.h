// The CPU reference renderer (docs/accuracy.md): the same conventions as the GL ray caster, in
// double precision, multithreaded over rows.
//  (a) `render_reference` at a given step: the same algorithm as the GPU (post-classification,
//      peak finding with the same table and regula falsi, or the same preintegration table), to
//      check the GL path;
//  (b) `render_converged`: the optical model itself. The ray is cut at voxel-cell faces and at
//      the exact crossings of every TF breakpoint (ray_events.h), so each piece is smooth; pieces
//      are integrated by the midpoint rule, refined until the image changes < tolerance. The
//      peak model adds, at every exact crossing of a peak value, a surface with the peak's colour
//      and unscaled opacity, composited in ray order.
#pragma once

#include "core/image.h"
#include "core/scene.h"
#include "core/volume.h"

namespace peakcast::reference {

struct ReferenceOptions {
  double step = 0.0;        // 0: the scene's step (uniform sampling only)
  double step_scale = 1.0;  // the plan coarsened like an interactive frame (core/sampling.h)
  bool early_termination = true;
};

Image render_reference(const Volume& v, const ResolvedScene& s, const ReferenceOptions& options = {});

// Which point along a probe's ray is its answer. Surface (the default): the first sample whose
// value the TF gives at least kPickOpacity (VTK's vtkVolumePicker and its opacity isovalue,
// 0.05), so a click on a translucent edge lands on its front; where no sample is that opaque,
// the half-opacity point. Half: where the ray's accumulated opacity first passes one half.
enum class ProbePick { Surface, Half };
constexpr double kPickOpacity = 0.05;
const char* to_string(ProbePick p);
ProbePick parse_probe_pick(const std::string& name);  // "surface" | "half"; std::invalid_argument

// What lies under one pixel (the viewer's probe, POST /api/probe): the reference ray of the
// scene's method, and the point `pick` names along it. `value` is the data value drawn there (a
// peak's value at a peak surface). Adaptive sampling is replaced by the uniform step. Throws
// std::invalid_argument for a pixel outside the image or a volume without voxels (a distributed
// volume on the serving rank).
struct ProbeResult {
  bool hit = false;
  ProbePick pick = ProbePick::Half;  // which point was answered (a surface pick without one: Half)
  glm::dvec3 position{0.0};          // world units (docs/scenes.md)
  double value = 0.0;
  double distance = 0.0;  // from the eye (the image plane for orthographic views) along the ray
  double opacity = 0.0;   // the ray's whole accumulated opacity
};
ProbeResult probe_reference(const Volume& v, const ResolvedScene& s, int x, int y, ProbePick pick = ProbePick::Surface);
// The probe's answer for every pixel (REST ?format=depth): `distance` where the ray's opacity
// passes one half, NaN where it never does; width * height floats, row 0 at the top.
std::vector<float> depth_reference(const Volume& v, const ResolvedScene& s);

enum class OpticalModel { Dvr, Peaks };

struct ConvergedImage {
  Image image;
  double step = 0.0;         // finest midpoint step used
  double last_change = 0.0;  // max abs RGB change between the last two refinements
  int refinements = 0;
  bool converged = false;
};

ConvergedImage render_converged(const Volume& v, const ResolvedScene& s, OpticalModel model = OpticalModel::Dvr,
                                double tolerance = 1e-4, double min_step_voxels = 1.0 / 64.0);

}  // namespace peakcast::reference
