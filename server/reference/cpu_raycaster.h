// The CPU reference renderer (DESIGN §4): the same conventions as the GL ray caster, in double
// precision, multithreaded over rows.
//  (a) `render_reference` at a given step: the same algorithm as the GPU, to check it;
//  (b) `render_converged`: the emission-absorption integral of the DVR model, by refining the
//      step (midpoint rule, early termination off) until the image changes < tolerance.
#pragma once

#include "core/image.h"
#include "core/scene.h"
#include "core/volume.h"

namespace peakcast::reference {

struct ReferenceOptions {
  double step = 0.0;  // 0: the scene's step
  bool early_termination = true;
  bool midpoint = false;  // samples at t_enter + (i + 1/2) step, for the converged integral
};

Image render_reference(const Volume& v, const ResolvedScene& s, const ReferenceOptions& options = {});

struct ConvergedImage {
  Image image;
  double step = 0.0;
  double last_change = 0.0;  // max abs RGB change between the last two refinements
  int refinements = 0;
  bool converged = false;
};

ConvergedImage render_converged(const Volume& v, const ResolvedScene& s, double tolerance = 1e-4,
                                double min_step_voxels = 1.0 / 64.0);

}  // namespace peakcast::reference
