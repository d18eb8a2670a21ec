// POST /api/render (docs/rest.md): a scene checked, its volume loaded on the loader pool when it
// is not yet, queued as a still on the render thread, answered when drawn. A pyramid held coarser
// than its finest level (serve --memory-budget-mib) draws the finest brick after brick.
#pragma once

#include "net/rest_routes.h"

namespace peakcast::net {

void render_still(AppContext& app, const Request& req, std::function<void(Response)> send,
                  std::shared_ptr<std::atomic<bool>> cancelled);

// The refusal of a still (or a movie's frame) whose estimated samples pass max_still_samples, in
// words naming the limit; "" when it is within it.
std::string still_cost_refusal(const AppContext& app, const ResolvedScene& scene);

// A message about a volume's files (a chunk of its finest level) as a client may read it: the
// server's path of the volume replaced by its id.
std::string without_volume_path(const VolumeEntry& entry, std::string message);

}  // namespace peakcast::net
