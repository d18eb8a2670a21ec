// peakcast-bench's ceiling for the ray caster (its programs' entry points,
// bench_raycast_bare.frag and .comp, are drawn only by the benchmark's renderer:
// server/gpu/bench_bare_renderer.cpp): the same rays and the same number of samples as a full
// render (its per-pixel sample counts arrive in u_budget), reconstruction only: no TF, no
// compositing.
layout(binding = UNIT_BUDGET) uniform sampler2D u_budget;

RayState cast_ray_bare(vec2 pixel, ivec2 texel) {
  RayState res = RayState(vec4(0.0), 0.0, P.stop, 1.0, 1.0, true, 0.0, 0.0, false, false, 0.0, 0.0);
  Ray r = make_ray(pixel);
  vec2 span = intersect_box(r);
  int budget = int(texelFetch(u_budget, texel, 0).r);
  float sum = 0.0;
  Lattice L = ray_lattice(r, span.x);
  for (int i = 0; i < budget; ++i) sum += sample_field(r, voxel_at(r, lattice_t(L, float(i))));
  res.acc = vec4(sum * 1e-9);  // keeps the loop from being optimised away
  res.samples = float(budget);
  return res;
}
