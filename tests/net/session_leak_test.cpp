// The network and session layers without GL: 1000 WebSocket sessions
// opened (hello, welcome, camera, TF, render settings, ping/pong) and closed, half with a close
// frame, half by dropping the TCP connection, against the real listener, HTTP upgrade,
// WebSocket session, session registry and scheduler; the render thread is not started, so no
// GL runs. Every count returns to zero, and under scripts/test.sh this binary runs in the unit
// label under ASan with the leak checker on: a per-session leak anywhere in those layers fails
// it by name.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "core/generators.h"
#include "net/beast.h"
#include "net/listener.h"
#include "net/ws_session.h"

using namespace peakcast;
using namespace peakcast::net;
using nlohmann::json;

namespace {

std::string read_text(websocket::stream<tcp::socket>& ws) {
  beast::flat_buffer buf;
  for (;;) {
    ws.read(buf);
    if (ws.got_text()) return beast::buffers_to_string(buf.data());
    buf.consume(buf.size());
  }
}

TEST(SessionLeaks, ThousandSessionsOpenAndCloseWithoutGl) {
  const auto dir = std::filesystem::temp_directory_path() / ("peakcast_leak_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  GeneratorSpec g;
  g.dims = {24, 24, 24};
  generate_to_file(g, dir / "blobs.raw");

  ServerConfig cfg;
  cfg.port = 0;
  cfg.data_dirs = {dir};
  cfg.volumes = {dir / "blobs.raw"};
  cfg.max_sessions = 8;
  {
    AppContext app(cfg);
    app.volumes.preload(dir / "blobs.raw");
    asio::io_context ioc(1);
    auto listener = std::make_shared<Listener>(ioc, tcp::endpoint{asio::ip::make_address("127.0.0.1"), 0}, app);
    const uint16_t port = listener->port();
    listener->run();
    std::thread io([&] { ioc.run(); });

    constexpr int kSessions = 1000;
    int welcomed = 0, pongs = 0;
    for (int i = 0; i < kSessions; ++i) {
      asio::io_context cio;
      websocket::stream<tcp::socket> ws(cio);
      ws.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
      ws.next_layer().set_option(tcp::no_delay(true));  // no 40 ms Nagle/delayed-ACK stall per message
      ws.handshake("127.0.0.1", "/ws");
      ws.text(true);
      ws.write(asio::buffer(json{{"type", "hello"}, {"viewport", {{"width", 64}, {"height", 48}}}}.dump()));
      const json welcome = json::parse(read_text(ws));
      welcomed += welcome["type"] == "welcome";
      ws.write(asio::buffer(json{{"type", "camera"}, {"camera", welcome["state"]["camera"]}}.dump()));
      ws.write(asio::buffer(
          json{{"type", "tf"}, {"version", 2 + i}, {"tf", {{"points", {{0, 0, 0, 0, 0}, {255, 1, 1, 1, 0.5}}}}}}
              .dump()));
      ws.write(asio::buffer(json{{"type", "render"}, {"render", {{"shading", i % 2 == 0}}}}.dump()));
      ws.write(asio::buffer(json{{"type", "ping"}, {"id", std::to_string(i)}}.dump()));
      for (;;) {
        const json m = json::parse(read_text(ws));
        if (m["type"] == "pong") {
          pongs += m["id"] == std::to_string(i);
          break;
        }
      }
      if (i % 2 == 0) {
        ws.close(websocket::close_code::normal);
      } else {
        beast::error_code ec;
        ws.next_layer().close(ec);  // vanished: no close frame
      }
    }
    EXPECT_EQ(welcomed, kSessions);
    EXPECT_EQ(pongs, kSessions);
    for (int k = 0; k < 300 && (app.ws_sessions.count() > 0 || app.render.session_count() > 0); ++k)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_EQ(app.ws_sessions.count(), 0);
    EXPECT_EQ(app.render.session_count(), 0u);

    listener->stop();
    for (auto& s : app.ws_sessions.live()) s->shut_down();
    ioc.stop();
    io.join();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
