// The volume and scene several benchmarks share (bench raycast's): blobs 256^3 (or any volume
// file, or a generator kind), four TF points over the range, a three-quarter view.
#pragma once

#include <memory>
#include <string>

#include "core/scene.h"
#include "core/volume.h"
#include "bench/bare_sampling.h"
#include "render/backend.h"

namespace peakcast::bench {

// A file, or a generator kind made in memory at a modest size (ML 128^3, the others 256^3).
std::shared_ptr<Volume> bench_volume(const std::string& what);
ResolvedScene bench_scene(const Volume& vol, int size, const std::string& filter);
// The camera turned by `deg` about its up axis through the centre (an orbit).
Camera orbit_camera(const Camera& c, double deg);

// The renderer a benchmark draws with: PEAKCAST_BACKEND's (auto: the CPU backend on a software
// rasteriser), its line printed; the product's renderer with the bare sampling loop and the
// renderer's switches added (`bench`: the same object).
struct BenchRenderer : render::RenderBackend {
  BareSampling* bench = nullptr;
};
BenchRenderer make_bench_renderer();

}  // namespace peakcast::bench
