// POST /api/slice (docs/rest.md, "Slices"): a scene plus "slice", answered with the slice's PNG.
#pragma once

#include "net/rest_routes.h"

namespace peakcast::net {

void slice_still(AppContext& app, const Request& req, std::function<void(Response)> send);

}  // namespace peakcast::net
