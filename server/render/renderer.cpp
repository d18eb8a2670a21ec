#include "render/renderer.h"

#include <stdexcept>

namespace peakcast::render {

void Renderer::check_submit(const RenderRequest& request, size_t in_flight) {
  if (request.output != RenderOutput::Rgb8 || request.tile)
    throw std::invalid_argument("submit: whole 8-bit frames only (render() draws tiles and float images)");
  if (in_flight >= kFramesInFlight)
    throw std::logic_error("submit: " + std::to_string(kFramesInFlight) + " frames in flight already: collect first");
}

void Renderer::submit(const ResidentVolume& volume, const ResolvedScene& scene, const RenderRequest& request) {
  check_submit(request, in_flight());
  Done d;
  d.result = render(volume, scene, request, &d.stats);
  done_.push_back(std::move(d));
}

RenderResult Renderer::collect(RenderStats* stats) {
  if (done_.empty()) throw std::logic_error("collect: no frame was submitted");
  Done d = std::move(done_.front());
  done_.pop_front();
  if (stats) *stats = std::move(d.stats);
  return std::move(d.result);
}

}  // namespace peakcast::render
