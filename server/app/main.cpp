// crackvis-render: remote rendering sessions of DEM data and their crack
// surfaces, streamed as H.264 over gRPC with mutual TLS, reading through
// crackvis-data. Parses options, wires a RenderServer, waits for SIGINT or
// SIGTERM. With --snapshot it renders one picture and exits (no client, no
// server: for scripts and tests). docs/protocol.md describes the service.
#include <csignal>
#include <cstdio>
#include <exception>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include <crackvis/common/data_root.hpp>
#include <crackvis/common/huge_pages.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/common/service_manager.hpp>
#include <crackvis/common/termination.hpp>
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/render/probe_scene.hpp>
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/rpc_server/setting_check.hpp>
#include <crackvis/rpc_server/user_list.hpp>
#include <crackvis/service/render_server.hpp>

namespace {

using crackvis::Result;
using crackvis::Status;
using crackvis::service::RenderServerConfig;

enum ExitCode : int { kExitOk = 0, kExitFailure = 1, kExitUsage = 2 };

int fail(const std::string& message) {
  std::fprintf(stderr, "crackvis-render: %s\n", message.c_str());
  return kExitFailure;
}

constexpr std::int64_t kDescriptionStep = -2;  // --step not given: the description's

struct Flags {
  std::string usersFrom;
  std::string snapshot;
  std::string output;
  std::string dataRoot;
  std::int64_t step = kDescriptionStep;
  int width = 0;
  int height = 0;
};

Result<std::string> readText(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    return crackvis::notFound(fmt::format("{}: cannot read the file", path));
  }
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// One picture through the same session code the service runs.
int snapshot(const Flags& flags, const RenderServerConfig& config) {
  using namespace crackvis;
  auto xml = readText(flags.snapshot);
  if (!xml) {
    return fail(xml.status().message());
  }
  auto description = pipeline::parsePipeline(*xml);
  if (!description) {
    return fail(fmt::format("{}: {}", flags.snapshot, description.status().message()));
  }
  if (flags.step != kDescriptionStep) {
    description->step = flags.step;
  }
  if (flags.width > 0) {
    description->view.width = flags.width;
  }
  if (flags.height > 0) {
    description->view.height = flags.height;
  }
  service::Session::SourceOpener opener;
  std::optional<dataservice::DataClient> client;
  if (!flags.dataRoot.empty()) {
    auto root = DataRoot::open(flags.dataRoot);
    if (!root) {
      return fail(root.status().message());
    }
    auto resolved = root->resolveFile(description->file);
    if (!resolved) {
      return fail(resolved.status().message());
    }
    // Opened here, before the session starts its threads: the guarded open
    // forks, and a child forked beside running threads may wait forever on
    // a lock one of them held (ASan's allocator's did, in the test suite).
    auto opened = source::openLocalSource(resolved->absolute, config.limits.fileSizes,
                                          source::LocalOpen::kStructureInChild);
    if (!opened) {
      return fail(opened.status().message());
    }
    auto first = std::make_shared<std::unique_ptr<source::StepSource>>(std::move(opened).value());
    opener = [first, file = description->file](
                 const std::string& asked) -> Result<std::unique_ptr<source::StepSource>> {
      if (asked != file) {
        return crackvis::failedPrecondition(
            fmt::format("a snapshot reads {} alone, not {}", file, asked));
      }
      if (!*first) {
        return crackvis::failedPrecondition(fmt::format("a snapshot opens {} once", file));
      }
      return std::move(*first);
    };
  } else {
    auto connected = dataservice::DataClient::connect(config.data);
    if (!connected) {
      return fail(connected.status().message());
    }
    opener = [client = std::move(connected).value(), sizes = config.limits.fileSizes](
                 const std::string& file) { return source::openRemoteSource(client, file, sizes); };
  }
  auto session = service::Session::open("snapshot", *description, opener, config.limits);
  if (!session) {
    return fail(session.status().message());
  }
  int step = 0;
  auto image = (*session)->snapshot(0, 0, &step);
  if (!image) {
    return fail(image.status().message());
  }
  if (Status status = render::writePng(*image, flags.output); !status) {
    return fail(status.message());
  }
  std::printf("wrote %s: %s step %d, %dx%d, %s\n", flags.output.c_str(), description->file.c_str(),
              step, image->width, image->height, (*session)->info().backend.c_str());
  return kExitOk;
}

// A bug's exception ends the process with one line and status 1, not an
// abort: expected failures are Status values and never get here.
template <typename Run>
int runGuarded(Run run) {
  try {
    return run();
  } catch (const std::exception& e) {
    return fail(fmt::format("internal error: {}", e.what()));
  }
}

// The heap reserve in effect, and why none where one was asked for.
std::string heapReserveText(const RenderServerConfig& config, std::size_t bytes) {
  if (bytes > 0) {
    return fmt::format("{} MiB", bytes >> 20);
  }
  return config.heapReserveMb > 0 ? "none (threads have heaps of their own)" : "none";
}

int serve(const RenderServerConfig& config) {
  const crackvis::TerminationSignals signals;
  crackvis::encode::limitCodecLogsToWarnings();

  // The rendering backend is chosen now, with a clear error if neither
  // Mesa's surfaceless platform nor an EGL device works, not at the first
  // session.
  auto probe = crackvis::render::SceneRenderer::create(64, 64);
  if (!probe) {
    return fail(probe.status().message());
  }
  // One frame of a small cracked specimen too: a driver that makes a
  // context but cannot draw fails here, and its shader compiler is loaded
  // before the first user waits for it.
  crackvis::render::Image frame;
  if (crackvis::Status drawn = crackvis::render::renderProbeScene(**probe, 64, 64, frame); !drawn) {
    return fail("drawing the start-up probe frame: " + drawn.message());
  }
  crackvis::log::event(
      stdout, "crackvis-render", "start",
      {{"version", CRACKVIS_VERSION}, {"grpc", grpc::Version()}, {"backend", (*probe)->backend()}});
  probe->reset();
  auto server = crackvis::service::RenderServer::start(config);
  if (!server) {
    return fail(server.status().message());
  }
  crackvis::log::event(stdout, "crackvis-render", "serving",
                       {{"address", (*server)->address()},
                        {"tls", config.insecure ? "none (INSECURE, loopback only)" : "mutual"},
                        {"data_service", config.data.target},
                        {"max_sessions", std::to_string(config.maxSessions)},
                        {"heap_reserve", heapReserveText(config, (*server)->heapReserveBytes())}});
  if (!config.web.listen.empty()) {
    // The URL a person opens; "localhost" rather than 127.0.0.1 so that the
    // page is a secure context even on plaintext loopback.
    const std::string host =
        config.web.listen.rfind("127.0.0.1:", 0) == 0 || config.web.listen.rfind("0.0.0.0:", 0) == 0
            ? "localhost"
            : (*server)->webAddress().substr(0, (*server)->webAddress().rfind(':'));
    crackvis::log::event(stdout, "crackvis-render", "web_serving",
                         {{"address", (*server)->webAddress()},
                          {"url", fmt::format("{}://{}:{}/", config.insecure ? "http" : "https",
                                              host, (*server)->webPort())}});
  }
  std::fflush(stdout);
  crackvis::service_manager::notify("READY=1\nSTATUS=serving " + (*server)->address());
  const int signal = signals.wait();
  crackvis::service_manager::notify("STOPPING=1");
  crackvis::log::event(stderr, "crackvis-render", "stop",
                       {{"signal", std::to_string(signal)},
                        {"sessions_closed", std::to_string((*server)->sessionCount())}});
  (*server)->shutdown();
  return kExitOk;
}

}  // namespace

// The value of -c/--config on the command line, if any.
static std::string configPath(int argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-c" || arg == "--config") {
      return argv[i + 1];
    }
  }
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--config=", 0) == 0) {
      return arg.substr(9);
    }
  }
  return {};
}

int main(int argc, char** argv) {
  // Before anything else: tunables are read when a process starts.
  crackvis::reexecWithHugePages(argv);
  CLI::App app{
      "crackvis-render: remote rendering of DEM data and crack surfaces over gRPC with mutual\n"
      "TLS. Sessions assemble a pipeline description (pipeline-schemas/pipeline.xsd), read\n"
      "steps through crackvis-data (partial reads, step cache, prefetch), extract cracks,\n"
      "render off screen under EGL (Mesa llvmpipe or an NVIDIA GPU) and stream H.264.\n"
      "Certificates: certs/make-dev-certs.sh --client crackvis-render; docs/protocol.md.",
      "crackvis-render"};
  // The rendering backend needs an EGL context: it is printed at start-up.
  app.set_version_flag("--version",
                       fmt::format("crackvis-render {} (gRPC {}, libavcodec {})", CRACKVIS_VERSION,
                                   grpc::Version(), crackvis::encode::codecLibraryVersion()));
  // The configuration file first: options bound to its values below are
  // overwritten only by the flags actually given (CLI11 assigns no default).
  RenderServerConfig config;
  Flags flags;
  if (const std::string path = configPath(argc, argv); !path.empty()) {
    auto loaded = crackvis::service::loadRenderServerConfig(path);
    if (!loaded) {
      return fail(loaded.status().message());
    }
    config = std::move(loaded).value();
  }
  std::string configFile;
  app.add_option("-c,--config", configFile,
                 "JSON configuration file (listen, tls, insecure, users_from, data_service, "
                 "limits, access_log, web; deploy/config/render.json); flags override it");
  app.add_option("--listen", config.listen, "host:port to listen on (port 0 lets the OS choose)")
      ->capture_default_str();
  app.add_option("--ca", config.tls.ca, "CA certificate that signs client certificates")
      ->capture_default_str();
  app.add_option("--cert", config.tls.cert, "this server's certificate")->capture_default_str();
  app.add_option("--key", config.tls.key, "this server's private key")->capture_default_str();
  app.add_flag("--insecure", config.insecure,
               "plaintext without certificates; refuses any address but loopback");
  app.add_option("--users-from", flags.usersFrom,
                 "a crackvis-data JSON configuration whose users (tokens, passwords, folders) "
                 "apply here too");
  app.add_option("--data-server", config.data.target, "crackvis-data's host:port")
      ->capture_default_str();
  app.add_option("--data-ca", config.data.tls.ca, "CA that signs crackvis-data's certificate")
      ->capture_default_str();
  app.add_option("--data-cert", config.data.tls.cert,
                 "this server's client certificate for crackvis-data")
      ->capture_default_str();
  app.add_option("--data-key", config.data.tls.key, "its private key")->capture_default_str();
  app.add_option("--data-token", config.data.token,
                 "bearer token for crackvis-data, if it has users");
  app.add_option("--data-server-name", config.data.serverName,
                 "name crackvis-data's certificate must carry (default: the --data-server host)");
  app.add_flag("--data-insecure", config.data.insecure,
               "crackvis-data runs with --insecure (plaintext, loopback)");
  app.add_option("--max-sessions", config.maxSessions, "sessions open at once")
      ->capture_default_str();
  app.add_option("--max-sessions-per-user", config.maxSessionsPerUser,
                 "sessions one configured user may have open at once")
      ->capture_default_str();
  app.add_option("--session-grace", config.sessionGraceSeconds,
                 "seconds a session without a stream is kept for a reconnect")
      ->capture_default_str();
  app.add_option("--attach-seconds", config.attachSeconds,
                 "a stream that has not attached to a session within this time is cancelled")
      ->capture_default_str();
  app.add_option("--kept-renderers", config.keptRenderers,
                 "renderers (GL contexts, about 35 MB each at 1280x720) of ended sessions kept "
                 "for the next session of the same view size, one made at start, so that a "
                 "first picture does not wait for making one (0: every session makes its own)")
      ->capture_default_str();
  app.add_option("--heap-reserve-mb", config.heapReserveMb,
                 "MiB of heap kept resident while idle (written at start, kept back from each "
                 "trim of the heap) for the next session's arrays, so that a first picture does "
                 "not wait for the kernel to zero fresh pages (0: none)")
      ->capture_default_str();
  app.add_option("--heap-trim-after-ms", config.heapTrimAfterMs,
                 "what ended sessions freed beyond the heap reserve goes back to the system "
                 "once no session has ended for this long (a trim before the next open makes "
                 "its first picture fault those pages in again)")
      ->capture_default_str();
  app.add_option("--refine-after-ms", config.limits.refineAfterMs,
                 "full-resolution frame this long after the last event")
      ->capture_default_str();
  app.add_option("--interactive-frame-ms", config.limits.interactiveFrameMs,
                 "budget of a reduced-resolution frame while interacting: its wait for a render "
                 "turn and its render")
      ->capture_default_str();
  app.add_option("--max-reduction", config.limits.maxReduction,
                 "largest image reduction factor while interacting (1: always full resolution)")
      ->capture_default_str();
  app.add_option("--renders-at-once", config.limits.rendersAtOnce,
                 "frames of all sessions rendered at the same time; the others wait their turn, "
                 "first come first served (0: the hardware threads)")
      ->capture_default_str();
  app.add_option("--max-particles", config.limits.fileSizes.maxParticles,
                 "refuse files declaring more particles (before allocating for them)")
      ->capture_default_str();
  app.add_option("--max-bonds", config.limits.fileSizes.maxBonds,
                 "refuse files declaring more bonds (before allocating for them)")
      ->capture_default_str();
  app.add_option("--access-log", config.accessLog, "file for access lines; - stderr; empty none")
      ->capture_default_str();
  app.add_option("--web-listen", config.web.listen,
                 "host:port of the browser page (HTTPS with --cert/--key, and a WebSocket per "
                 "stream); needs users (--users-from): the page signs in with a password or token");
  app.add_option("--web-root", config.web.root,
                 "the page's folder (default: share/crackvis/web beside the program, else the "
                 "build tree's web/dist)");
  app.add_option("--web-origin", config.web.origins,
                 "another origin whose page may call, e.g. a proxy's https://viz.example.org "
                 "(repeatable; the page's own is always allowed)");
  auto* snapshotOption =
      app.add_option("--snapshot", flags.snapshot,
                     "render PIPELINE.xml once, write -o OUT.png and exit (no server)");
  app.add_option("-o,--output", flags.output, "PNG file of --snapshot")->needs(snapshotOption);
  app.add_option("--data-root", flags.dataRoot,
                 "with --snapshot: read files from this folder instead of crackvis-data")
      ->needs(snapshotOption);
  app.add_option("--step", flags.step, "with --snapshot: the step (-1 the last)")
      ->needs(snapshotOption);
  app.add_option("--width", flags.width, "with --snapshot: image width")
      ->needs(snapshotOption)
      ->check(CLI::Range(16, 3840));
  app.add_option("--height", flags.height, "with --snapshot: image height")
      ->needs(snapshotOption)
      ->check(CLI::Range(16, 2160));
  app.footer(
      "Example: crackvis-render --listen 127.0.0.1:50052 --data-server localhost:50051\n"
      "         crackvis-render ... --users-from data.json --web-listen 0.0.0.0:8443\n"
      "         crackvis-render --snapshot view.xml --data-root /data -o view.png");
  CLI11_PARSE(app, argc, argv);
  if (!flags.usersFrom.empty()) {
    auto users = crackvis::rpc::loadUsersFrom(flags.usersFrom);
    if (!users) {
      return fail(users.status().message());
    }
    config.users = std::move(users).value();
  }
  // Checked once merged, so a flag and a file value meet the same rules.
  if (Status valid = crackvis::service::validateRenderServerConfig(config); !valid) {
    return fail(valid.message());
  }
  if (!flags.snapshot.empty()) {
    if (flags.output.empty()) {
      return fail("--snapshot needs -o OUT.png");
    }
    if (flags.step != kDescriptionStep) {
      // Steps are int indices: a wider value must not wrap.
      if (Status valid = crackvis::rpc::checkSetting<std::int64_t>({"--step", ""}, flags.step, -1,
                                                                   std::numeric_limits<int>::max());
          !valid) {
        return fail(valid.message());
      }
    }
    return runGuarded([&] { return snapshot(flags, config); });
  }
  return runGuarded([&] { return serve(config); });
}
