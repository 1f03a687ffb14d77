#include "service/render_fixture.hpp"

#include <filesystem>
#include <fstream>
#include <mutex>

#include <catch2/catch.hpp>

#include "dataservice/service_fixture.hpp"
#include "support/simulated_cuboid.hpp"

namespace crackvis::testing {

const TempDir& crackRoot() {
  static TempDir dir;
  static std::once_flag once;
  std::call_once(once, [] {
    writeSimulatedCuboidA(dir.file("cuboidA.h5"));
    std::ofstream(dir.file("notes.txt")) << "not HDF5\n";
    namespace fs = std::filesystem;
    fs::create_directories(dir.path() / "alice");
    fs::create_directories(dir.path() / "bob");
    fs::copy_file(dir.path() / "cuboidA.h5", dir.path() / "alice" / "a.h5");
    fs::copy_file(dir.path() / "cuboidA.h5", dir.path() / "bob" / "b.h5");
    fs::create_symlink("../bob/b.h5", dir.path() / "alice" / "link.h5");
    fs::create_symlink("a.h5", dir.path() / "alice" / "swap.h5");
  });
  return dir;
}

service::RenderServerConfig renderConfig(const dataservice::DataServer& data) {
  service::RenderServerConfig config;
  config.listen = "127.0.0.1:0";
  config.tls = serverTls();
  config.data.target = data.address();
  config.data.tls = clientTls("crackvis-render");
  config.accessLog = "";
  return config;
}

std::unique_ptr<service::RenderServer> startRenderServer(
    const service::RenderServerConfig& config) {
  auto render = service::RenderServer::start(config);
  INFO(render.status().message());
  REQUIRE(render.isOk());
  return std::move(render).value();
}

namespace {

std::unique_ptr<service::RenderServer> startRender(const dataservice::DataServer& data,
                                                   const std::string& listen, double graceSeconds,
                                                   int maxSessions,
                                                   std::vector<dataservice::UserEntry> users,
                                                   const std::string& accessLog) {
  service::RenderServerConfig config = renderConfig(data);
  config.listen = listen;
  config.sessionGraceSeconds = graceSeconds;
  config.maxSessions = maxSessions;
  config.users = std::move(users);
  config.accessLog = accessLog;
  return startRenderServer(config);
}

}  // namespace

std::unique_ptr<service::RenderServer> startRenderServer(const dataservice::DataServer& data,
                                                         const std::string& listen,
                                                         double graceSeconds) {
  return startRender(data, listen, graceSeconds, 8, {}, "");
}

Services startServices(double graceSeconds, int maxSessions,
                       std::vector<dataservice::UserEntry> users, const std::string& accessLog) {
  Services services;
  auto dataConfig = baseConfig();
  dataConfig.dataRoot = crackRoot().path().string();
  services.data = startServer(dataConfig);
  services.render = startRender(*services.data, "127.0.0.1:0", graceSeconds, maxSessions,
                                std::move(users), accessLog);
  return services;
}

pipeline::PipelineDescription crackView() {
  pipeline::PipelineDescription d;
  d.file = "cuboidA.h5";
  d.step = -1;
  d.view.width = 320;
  d.view.height = 240;
  d.view.background = {0, 0, 0};
  d.view.scalarBar = false;
  // Pictures are checked by counting colours: the triad's red, green and
  // yellow axes would count (annotations in a session: their own test).
  d.annotations.show = false;
  d.particles.visible = false;
  d.cracks.colour = {255, 0, 0};
  return d;
}

}  // namespace crackvis::testing
