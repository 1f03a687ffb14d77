// What the render server's and the client's tests share: a data root with a
// scaled simulated cuboid A, real crackvis-data and crackvis-render started
// in this process on loopback ports with generated certificates, and a small
// view of the cracks.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "support/temp_dir.hpp"
#include <crackvis/dataservice_service/data_server.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/service/render_server.hpp>

namespace crackvis::testing {

// cuboidA.h5 (cuboid3d A at scale 0.3, made once per process), notes.txt,
// and users' folders: alice/a.h5 and bob/b.h5 (copies of cuboidA.h5),
// alice/link.h5 -> ../bob/b.h5 and alice/swap.h5 -> a.h5 (re-pointed by a test).
const TempDir& crackRoot();

struct Services {
  std::unique_ptr<dataservice::DataServer> data;
  std::unique_ptr<service::RenderServer> render;
};

// `accessLog`: the render server's access log ("": none).
Services startServices(double graceSeconds = 30.0, int maxSessions = 8,
                       std::vector<dataservice::UserEntry> users = {},
                       const std::string& accessLog = "");
// A render server for an already running data service (a restart); `listen`
// may name the port the previous one had.
std::unique_ptr<service::RenderServer> startRenderServer(const dataservice::DataServer& data,
                                                         const std::string& listen,
                                                         double graceSeconds = 30.0);

// What startServices gives its render server (loopback, port 0, mutual TLS,
// no access log), for tests that change a limit, and a server started on it.
service::RenderServerConfig renderConfig(const dataservice::DataServer& data);
std::unique_ptr<service::RenderServer> startRenderServer(const service::RenderServerConfig& config);

// A 320x240 view of the file's last step: particles hidden, cracks red on black.
pipeline::PipelineDescription crackView();

}  // namespace crackvis::testing
