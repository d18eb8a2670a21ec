// POST /api/movie (docs/rest.md, "Movies"): a scene plus a camera path, rendered frame after
// frame on the render thread as stills and streamed back as the file is made (MP4, WebM or a
// ZIP of PNGs).
#pragma once

#include "net/rest_routes.h"

namespace peakcast::net {

void movie(AppContext& app, const Request& req, std::function<void(Response)> send,
           std::shared_ptr<std::atomic<bool>> cancelled, OpenStream open_stream);

}  // namespace peakcast::net
