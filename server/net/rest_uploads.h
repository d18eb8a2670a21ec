// Chunked uploads' routes (/api/uploads...; docs/rest.md, "Chunked uploads"). `client`: the
// remote address, for the upload rate.
#pragma once

#include <string>

#include "net/rest_routes.h"

namespace peakcast::net {

void uploads_route(AppContext& app, Request req, const std::string& client, std::function<void(Response)> send);

}  // namespace peakcast::net
