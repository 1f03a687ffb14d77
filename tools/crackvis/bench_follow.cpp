// crackvis bench follow: what a user watching a running simulation waits.
// Opens --sessions sessions on a live file (waiting for the writer to give it
// its name), each following its newest step, and records every frame as it
// arrives; at the end of the run (the writer closed the file) it matches the
// frames with the writer's step log (crackvis sim --step-log): for each step
// a session showed, the time from the step's commit to its first frame on
// the client. Also reports the session's extraction time per new step
// (incremental from the step shown before). tools/bench/live-follow.sh runs
// it beside a writer alone and followed, alternately.
#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <nlohmann/json.hpp>

#include "bench_support.hpp"
#include "commands.hpp"
#include "crackvis/v1/render.grpc.pb.h"
#include "pipeline_file.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/rpc/connection_advice.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/tls/channel.hpp>
#include <crackvis/tls/tls_material.hpp>
#include <crackvis/vocabulary/crack_method.hpp>

namespace crackvis::cli {
namespace {

namespace v1 = crackvis::v1;

struct FollowBenchOptions {
  std::string server;
  std::string file;
  std::string stepLog;
  int sessions = 1;
  std::string size = "1280x720";
  std::string method = "local-voronoi";
  double wait = 120.0;     // s for the file to appear
  double seconds = 900.0;  // s at most for the run
  tls::TlsFiles tls = tls::defaultTlsFiles("client");
  std::string token;
  bool jsonOnly = false;
};

double unixSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// One session's stream: the first frame of each step, with when it came.
struct StepFrame {
  double arrived = 0.0;  // Unix seconds
  double extractMs = 0.0;
  double loadMs = 0.0;
};

class Follower {
 public:
  Follower(v1::RenderService::Stub& stub, const std::string& session, const std::string& token)
      : m_session(session) {
    if (!token.empty()) {
      m_context.AddMetadata("authorization", "Bearer " + token);
    }
    m_stream = stub.Stream(&m_context);
    v1::ClientEvent attach;
    attach.set_attach_session_id(session);
    m_stream->Write(attach);
    m_reader = std::thread([this] { read(); });
  }
  ~Follower() {
    m_context.TryCancel();
    m_reader.join();
  }
  bool ended() {
    std::lock_guard lock(m_mutex);
    return m_ended || m_runEnded;
  }
  std::map<int, StepFrame> steps() {
    std::lock_guard lock(m_mutex);
    return m_steps;
  }
  std::vector<std::string> errors() {
    std::lock_guard lock(m_mutex);
    return m_errors;
  }

 private:
  void read() {
    v1::ServerMessage message;
    while (m_stream->Read(&message)) {
      const double arrived = unixSeconds();
      std::lock_guard lock(m_mutex);
      if (message.has_frame()) {
        const v1::Frame& frame = message.frame();
        // A frame that arrives with a new step: the step change's timings.
        m_steps.try_emplace(frame.step(), StepFrame{arrived, frame.timings().extract_ms(),
                                                    frame.timings().load_ms()});
      } else if (message.has_state()) {
        m_runEnded = m_runEnded || message.state().run_ended();
      } else if (message.has_error()) {
        m_errors.push_back(message.error().message());
      }
    }
    std::lock_guard lock(m_mutex);
    m_ended = true;
  }

  std::string m_session;
  grpc::ClientContext m_context;
  std::unique_ptr<grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>> m_stream;
  std::mutex m_mutex;
  std::map<int, StepFrame> m_steps;
  std::vector<std::string> m_errors;
  bool m_ended = false;
  bool m_runEnded = false;
  std::thread m_reader;
};

// The writer's log: step index -> commit time (Unix seconds).
Result<std::map<int, double>> readStepLog(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    return notFound(fmt::format("cannot read the step log {}", path));
  }
  std::map<int, double> commits;
  int step = 0;
  double at = 0.0;
  while (in >> step >> at) {
    commits[step] = at;
  }
  return commits;
}

// OpenSession, again and again until the writer has given the file its name.
Result<std::string> openWhenThere(v1::RenderService::Stub& stub, const FollowBenchOptions& options,
                                  const std::string& xml,
                                  const std::shared_ptr<grpc::Channel>& channel) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(options.wait);
  while (true) {
    grpc::ClientContext context;
    if (!options.token.empty()) {
      context.AddMetadata("authorization", "Bearer " + options.token);
    }
    v1::OpenSessionRequest request;
    request.set_pipeline_xml(xml);
    v1::OpenSessionResponse response;
    const grpc::Status status = stub.OpenSession(&context, request, &response);
    if (status.ok()) {
      return response.session_id();
    }
    if (status.error_code() != grpc::StatusCode::NOT_FOUND ||
        std::chrono::steady_clock::now() > deadline) {
      return rpc::fromGrpcStatus(status, "OpenSession", {rpc::ServerKind::kRender, options.server},
                                 channel);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

Result<nlohmann::json> run(const FollowBenchOptions& options) {
  CRACKVIS_RETURN_IF_ERROR(checkHostPort("--server", options.server));
  auto material = tls::loadTlsMaterial(options.tls);
  if (!material) {
    return material.status();
  }
  auto size = parseFrameSize(options.size);
  if (!size) {
    return size.status();
  }
  auto method = cracks::parseMethod(options.method);
  if (!method) {
    return method.status();
  }
  pipeline::PipelineDescription d;
  d.file = options.file;
  d.step = -1;  // the newest step: the session follows
  d.view.width = size->first;
  d.view.height = size->second;
  d.cracks.method = *method;
  tls::ChannelOptions channelOptions;
  channelOptions.target = options.server;
  channelOptions.material = *material;
  auto channel = tls::createChannel(channelOptions);
  if (!channel) {
    return channel.status();
  }
  // Its first call meets a connection (gRPC 1.51 can fail an attempt in
  // progress: rpc::awaitConnection).
  rpc::awaitConnection(**channel, options.server,
                       std::chrono::system_clock::now() + std::chrono::seconds(10));
  auto stub = v1::RenderService::NewStub(*channel);
  const LoadAverage loadBefore = loadAverage();
  std::vector<std::unique_ptr<Follower>> followers;
  for (int s = 0; s < options.sessions; ++s) {
    auto id = openWhenThere(*stub, options, pipeline::toXml(d), *channel);
    if (!id) {
      return id.status();
    }
    followers.push_back(std::make_unique<Follower>(*stub, *id, options.token));
  }
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(options.seconds);
  while (std::chrono::steady_clock::now() < deadline &&
         !std::all_of(followers.begin(), followers.end(), [](auto& f) { return f->ended(); })) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  auto commits = readStepLog(options.stepLog);
  if (!commits) {
    return commits.status();
  }
  std::vector<double> latencies;
  std::vector<double> extractMs;
  std::vector<double> loadMs;
  nlohmann::json perSession = nlohmann::json::array();
  for (auto& follower : followers) {
    int shown = 0;
    for (const auto& [step, frame] : follower->steps()) {
      const auto commit = commits->find(step);
      if (commit == commits->end() || step == 0) {
        continue;  // step 0 came with the session's opening, not by following
      }
      latencies.push_back(1000.0 * (frame.arrived - commit->second));
      extractMs.push_back(frame.extractMs);
      loadMs.push_back(frame.loadMs);
      ++shown;
    }
    perSession.push_back({{"steps_shown", shown}, {"errors", follower->errors()}});
  }
  followers.clear();
  return nlohmann::json{
      {"file", options.file},
      {"sessions", options.sessions},
      {"size", options.size},
      {"method", options.method},
      {"steps_written", commits->size()},
      {"per_session", perSession},
      {"step_to_frame_ms", summaryJson(latencies)},
      {"step_to_frame_p50_ms", percentile(latencies, 50.0)},
      {"step_to_frame_p95_ms", percentile(latencies, 95.0)},
      {"extract_ms_per_new_step", summaryJson(extractMs)},
      {"load_ms_per_new_step", summaryJson(loadMs)},
      {"load_before", toJson(loadBefore)},
      {"load_after", toJson(loadAverage())},
      {"machine", machineDescription()},
  };
}

}  // namespace

Command addBenchFollowCommand(CLI::App& bench) {
  auto options = std::make_shared<FollowBenchOptions>();
  auto* command = bench.add_subcommand(
      "follow",
      "Follow a live file as a writer adds steps (crackvis sim --live --step-log LOG): open "
      "--sessions sessions on its newest step once it exists, record each step's first frame, "
      "and when the writer closes the file report the time from each step's commit to its "
      "frame (p50, p95) and the sessions' extraction time per new step");
  command->add_option("--server", options->server, "crackvis-render address, HOST:PORT")
      ->required();
  command->add_option("--file", options->file, "the live file, under the data service's root")
      ->required();
  command->add_option("--step-log", options->stepLog, "the writer's --step-log")->required();
  command->add_option("--sessions", options->sessions, "sessions following the file")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  command->add_option("--size", options->size, "view size WIDTHxHEIGHT")->capture_default_str();
  command->add_option("-m,--method", options->method, "crack method")->capture_default_str();
  command->add_option("--wait", options->wait, "seconds to wait for the file to appear")
      ->capture_default_str();
  command->add_option("--seconds", options->seconds, "seconds at most to follow")
      ->capture_default_str();
  command->add_option("--ca", options->tls.ca, "CA certificate that signed the server's (PEM)")
      ->capture_default_str();
  command->add_option("--cert", options->tls.cert, "client certificate (PEM)")
      ->capture_default_str();
  command->add_option("--key", options->tls.key, "client private key (PEM)")->capture_default_str();
  command->add_option("--token", options->token, "bearer token, when the server has users");
  command->add_flag("--json", options->jsonOnly, "print only the JSON");
  return {command, [options] {
            auto report = run(*options);
            if (!report) {
              printError("bench follow", report.status().message());
              return kExitFailure;
            }
            if (!options->jsonOnly) {
              std::printf(
                  "followed %s with %d session(s) at %s: %zu steps written\n"
                  "step committed -> its first frame on the client: p50 %.0f ms, p95 %.0f ms\n"
                  "session extraction per new step (incremental): median %.1f ms; read %.1f "
                  "ms\n",
                  options->file.c_str(), options->sessions, options->size.c_str(),
                  static_cast<std::size_t>((*report)["steps_written"]),
                  static_cast<double>((*report)["step_to_frame_p50_ms"]),
                  static_cast<double>((*report)["step_to_frame_p95_ms"]),
                  static_cast<double>((*report)["extract_ms_per_new_step"]["p50"]),
                  static_cast<double>((*report)["load_ms_per_new_step"]["p50"]));
            }
            std::printf("%s\n", report->dump().c_str());
            return kExitOk;
          }};
}

}  // namespace crackvis::cli
