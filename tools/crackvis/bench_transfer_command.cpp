// crackvis bench transfer: what partial reads save, measured in one run
// against a running crackvis-data. Times (a) the whole file through Fetch,
// (b) a view's first step from nothing (Describe, then the Read of the
// step's positions and bond states with the bond list), also with every
// chunk raw (no packed integers), (c) a step change on that view (one
// Read), and (d) the whole file and the first view's wire bytes over a raw
// TLS socket with the same certificates (crackvis-data --raw-tls-listen),
// the physical baseline of the link. Rounds alternate their order and go on
// until the median ratios settle; prints bytes, seconds, MB/s, the ratios
// and the load as a table and as JSON.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench_support.hpp"
#include "commands.hpp"
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/dataservice_client/raw_tls_client.hpp>
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::cli {
namespace {

using Clock = std::chrono::steady_clock;
namespace ds = crackvis::dataservice;

struct TransferOptions {
  std::string server;
  std::string raw;
  std::string file;
  int step = -1;
  tls::TlsFiles tls = tls::defaultTlsFiles("client");
  std::string token;
  int repeat = 5;
  int maxRepeat = 30;
  double settle = 0.02;
  bool jsonOnly = false;
  // Only the view reads (b, c), --repeat rounds: for files too large to
  // fetch whole in a benchmark (tools/bench/scale.sh); no ratios.
  bool viewsOnly = false;
};

struct Timing {
  std::uint64_t bytes = 0;      // the arrays as the caller has them
  std::uint64_t wireBytes = 0;  // the data bytes that travelled (fewer when packed)
  std::vector<double> seconds;

  double median() const { return cli::median(seconds); }
  double best() const {
    return seconds.empty() ? 0.0 : *std::min_element(seconds.begin(), seconds.end());
  }
  double megabytesPerSecond() const {
    return median() > 0.0 ? static_cast<double>(bytes) / 1e6 / median() : 0.0;
  }
};

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The ratios of one round: each compares runs of the same round, so a slow
// stretch of the machine slows both sides of it.
struct RoundRatios {
  double fullOverFirstView = 0.0;
  double fullOverColdFirstView = 0.0;
  double fullOverWarmView = 0.0;
  double grpcOverRawFull = 0.0;  // throughput of the whole file
  double fullOverRawChunksFirstView = 0.0;
  double grpcOverRawFirstView = 0.0;  // the same wire bytes: raw TLS time / gRPC time
};

struct Report {
  std::string file;
  int step = 0;
  int warmStep = 0;
  std::string server;
  std::string raw;
  std::string tls;
  Timing describe;            // part of the first view: the server's held answer
  Timing coldDescribe;        // the server walks the file (its first Describe since it changed)
  Timing coldFirstView;       // the cold Describe + the first view's Read
  Timing firstView;           // Describe + the step's Read with the bond list
  Timing rawChunksFirstView;  // the same with every chunk raw (packing off)
  Timing warmView;            // another step's Read on the open file: a time step change
  Timing fetch;
  Timing rawFull;
  Timing rawView;  // the first view's wire bytes
  std::vector<RoundRatios> rounds;
  bool settled = false;
  LoadAverage loadBefore;
  LoadAverage loadAfter;
};

struct Connections {
  ds::DataClient client;
  ds::DataClient rawChunks;  // asks for every chunk raw: what packing saves
  ds::RawTlsOptions raw;
};

Result<Connections> connect(const TransferOptions& options, Report& report) {
  CRACKVIS_RETURN_IF_ERROR(checkHostPort("--server", options.server));
  // No default: in the documented layout the port after crackvis-data's is
  // crackvis-render's, not the raw TLS baseline's.
  if (!options.viewsOnly && options.raw.empty()) {
    return invalidArgument("--raw is required (the raw TLS baseline), unless --views-only");
  }
  if (!options.viewsOnly) {
    CRACKVIS_RETURN_IF_ERROR(checkHostPort("--raw", options.raw));
  }
  report.raw = options.raw;
  ds::ClientOptions clientOptions;
  clientOptions.target = options.server;
  clientOptions.tls = options.tls;
  clientOptions.token = options.token;
  clientOptions.timeoutSeconds = 3600.0;
  auto client = ds::DataClient::connect(clientOptions);
  if (!client) {
    return client.status();
  }
  CRACKVIS_RETURN_IF_ERROR(client->checkHealth());  // connects: no handshake in the timings
  clientOptions.packedReads = false;
  auto rawChunks = ds::DataClient::connect(clientOptions);
  if (!rawChunks) {
    return rawChunks.status();
  }
  CRACKVIS_RETURN_IF_ERROR(rawChunks->checkHealth());
  auto file = ds::RemoteDemFile::open(*client, options.file);
  if (!file) {
    return file.status();
  }
  if (file->stepCount() == 0) {
    return failedPrecondition(fmt::format("{} has no steps", options.file));
  }
  report.step = options.step < 0 ? file->stepCount() - 1 : options.step;
  if (report.step >= file->stepCount()) {
    return invalidArgument(fmt::format("--step {}: {} has steps 0..{}", report.step, options.file,
                                       file->stepCount() - 1));
  }
  // The step a user moves to next: the one before (after, at step 0).
  report.warmStep = report.step > 0 ? report.step - 1 : std::min(1, file->stepCount() - 1);
  ds::RawTlsOptions raw;
  raw.target = report.raw;
  raw.tls = clientOptions.tls;
  if (!options.token.empty()) {
    raw.authorization = "Bearer " + options.token;
  }
  return Connections{std::move(*client), std::move(*rawChunks), std::move(raw)};
}

// A view's first step from nothing, as crackvis-render's step source opens
// one: Describe (open) with the bond list asked for with it, then the Read
// of the step.
struct FirstView {
  ds::RemoteDemFile file;
  double describeSeconds = 0.0;
  double seconds = 0.0;         // Describe and Read
  std::uint64_t bytes = 0;      // positions, bond states and bond list as read
  std::uint64_t wireBytes = 0;  // as they travelled
};

Result<FirstView> openFirstView(const ds::DataClient& client, const Report& report) {
  const std::uint64_t wireBefore = client.readWireBytes();
  const auto start = Clock::now();
  auto view = ds::RemoteDemFile::open(client, report.file, {.prefetchBondList = true});
  if (!view) {
    return view.status();
  }
  const double describeSeconds = since(start);
  auto step = view->readStep(report.step);
  if (!step) {
    return step.status();
  }
  const double seconds = since(start);
  const std::uint64_t bytes = step->positions.size() * sizeof(dem::Vec3) + step->bondState.size() +
                              (*view->bonds())->size() * sizeof(dem::Bond);
  return FirstView{std::move(*view), describeSeconds, seconds, bytes,
                   client.readWireBytes() - wireBefore};
}

// The first view, then a step change on it: one more Read. Before them,
// the Describe of a file the server has not walked since it changed.
Status timeViews(const Connections& c, Report& report, bool timed) {
  auto start = Clock::now();
  auto cold = c.client.describe(report.file, true);
  if (!cold) {
    return cold.status();
  }
  const double coldSeconds = since(start);
  auto first = openFirstView(c.client, report);
  if (!first) {
    return first.status();
  }
  const std::uint64_t wireFirst = c.client.readWireBytes();
  start = Clock::now();
  auto next = first->file.readStep(report.warmStep);
  if (!next) {
    return next.status();
  }
  const double warmSeconds = since(start);
  if (timed) {
    report.describe.seconds.push_back(first->describeSeconds);
    report.coldDescribe.seconds.push_back(coldSeconds);
    report.firstView.seconds.push_back(first->seconds);
    report.coldFirstView.seconds.push_back(coldSeconds + first->seconds - first->describeSeconds);
    report.warmView.seconds.push_back(warmSeconds);
  }
  report.firstView.bytes = first->bytes;
  report.firstView.wireBytes = first->wireBytes;
  report.coldFirstView.bytes = first->bytes;
  report.coldFirstView.wireBytes = first->wireBytes;
  report.warmView.bytes = next->positions.size() * sizeof(dem::Vec3) + next->bondState.size();
  report.warmView.wireBytes = c.client.readWireBytes() - wireFirst;
  return Status::ok();
}

// The first view again, every chunk raw: what packed chunks save.
Status timeRawChunksView(const Connections& c, Report& report, bool timed) {
  auto first = openFirstView(c.rawChunks, report);
  if (!first) {
    return first.status();
  }
  if (timed) {
    report.rawChunksFirstView.seconds.push_back(first->seconds);
  }
  report.rawChunksFirstView.bytes = first->bytes;
  report.rawChunksFirstView.wireBytes = first->wireBytes;
  return Status::ok();
}

Status timeFetch(const Connections& c, Report& report, bool timed) {
  const auto start = Clock::now();
  auto fetched = c.client.fetch(report.file, {});
  if (!fetched) {
    return fetched.status();
  }
  if (timed) {
    report.fetch.seconds.push_back(since(start));
  }
  report.fetch.bytes = *fetched;
  report.fetch.wireBytes = *fetched;
  return Status::ok();
}

Status timeRaw(const Connections& c, Report& report, bool timed) {
  auto rawFull = ds::rawTlsRead(c.raw, report.file, 0, 0);
  if (!rawFull) {
    return Status(rawFull.status().code(),
                  fmt::format("raw TLS baseline at {} (start crackvis-data with "
                              "--raw-tls-listen, or give --raw): {}",
                              report.raw, rawFull.status().message()));
  }
  auto rawView = ds::rawTlsRead(c.raw, report.file, 0, report.firstView.wireBytes);
  if (!rawView) {
    return rawView.status();
  }
  if (timed) {
    report.rawFull.seconds.push_back(rawFull->transferSeconds);
    report.rawView.seconds.push_back(rawView->transferSeconds);
  }
  report.rawFull.bytes = rawFull->bytes;
  report.rawFull.wireBytes = rawFull->bytes;
  report.rawView.bytes = rawView->bytes;
  report.rawView.wireBytes = rawView->bytes;
  report.tls = rawFull->protocol + " " + rawFull->cipher;
  return Status::ok();
}

RoundRatios lastRound(const Report& r) {
  const double fetch = r.fetch.seconds.back();
  const double raw = r.rawFull.seconds.back();
  // Same bytes: a throughput ratio is raw time / gRPC time.
  return {fetch / r.firstView.seconds.back(),
          fetch / r.coldFirstView.seconds.back(),
          fetch / r.warmView.seconds.back(),
          fetch > 0.0 ? raw / fetch : 0.0,
          fetch / r.rawChunksFirstView.seconds.back(),
          r.rawView.seconds.back() / r.firstView.seconds.back()};
}

// The medians of the first `count` rounds' ratios, in RoundRatios' order:
// first view, cold first view, warm view, gRPC over raw TLS (whole file),
// first view with raw chunks, gRPC over raw TLS (first view).
std::array<double, 6> medianRatios(const std::vector<RoundRatios>& rounds, std::size_t count) {
  std::array<std::vector<double>, 6> values;
  for (std::size_t k = 0; k < count; ++k) {
    values[0].push_back(rounds[k].fullOverFirstView);
    values[1].push_back(rounds[k].fullOverColdFirstView);
    values[2].push_back(rounds[k].fullOverWarmView);
    values[3].push_back(rounds[k].grpcOverRawFull);
    values[4].push_back(rounds[k].fullOverRawChunksFirstView);
    values[5].push_back(rounds[k].grpcOverRawFirstView);
  }
  std::array<double, 6> medians{};
  for (std::size_t i = 0; i < medians.size(); ++i) {
    medians[i] = median(values[i]);
  }
  return medians;
}

// Settled: adding each of the last two rounds moved no median ratio by
// more than `settle` (relative).
bool settled(const std::vector<RoundRatios>& rounds, double settle) {
  if (rounds.size() < 3) {
    return false;
  }
  for (std::size_t n = rounds.size() - 1; n <= rounds.size(); ++n) {
    const auto before = medianRatios(rounds, n - 1);
    const auto after = medianRatios(rounds, n);
    for (std::size_t k = 0; k < after.size(); ++k) {
      if (std::abs(after[k] - before[k]) > settle * std::abs(before[k])) {
        return false;
      }
    }
  }
  return true;
}

// Rounds until the medians settle: the whole file through Fetch, a view's
// first and warm step, the raw TLS baseline; every other round in the
// reverse order, so that none of them always runs first. One untimed round
// first: the page cache and the connections are warm for every timed round.
Result<Report> measure(const TransferOptions& options) {
  Report report;
  report.file = options.file;
  report.server = options.server;
  auto connections = connect(options, report);
  if (!connections) {
    return connections.status();
  }
  report.loadBefore = loadAverage();
  if (options.viewsOnly) {
    for (int round = -1; round < options.repeat; ++round) {
      const bool timed = round >= 0;
      if (round % 2 == 0) {
        CRACKVIS_RETURN_IF_ERROR(timeViews(*connections, report, timed));
        CRACKVIS_RETURN_IF_ERROR(timeRawChunksView(*connections, report, timed));
      } else {
        CRACKVIS_RETURN_IF_ERROR(timeRawChunksView(*connections, report, timed));
        CRACKVIS_RETURN_IF_ERROR(timeViews(*connections, report, timed));
      }
    }
    report.loadAfter = loadAverage();
    return report;
  }
  for (int round = -1; round < options.maxRepeat; ++round) {
    const bool timed = round >= 0;
    const bool forward = round % 2 == 0;
    // The views first either way: the raw view's length is the first view's
    // wire bytes. The view with raw chunks before or after it.
    if (forward) {
      CRACKVIS_RETURN_IF_ERROR(timeViews(*connections, report, timed));
      CRACKVIS_RETURN_IF_ERROR(timeRawChunksView(*connections, report, timed));
    } else {
      CRACKVIS_RETURN_IF_ERROR(timeRawChunksView(*connections, report, timed));
      CRACKVIS_RETURN_IF_ERROR(timeViews(*connections, report, timed));
    }
    if (forward) {
      CRACKVIS_RETURN_IF_ERROR(timeFetch(*connections, report, timed));
      CRACKVIS_RETURN_IF_ERROR(timeRaw(*connections, report, timed));
    } else {
      CRACKVIS_RETURN_IF_ERROR(timeRaw(*connections, report, timed));
      CRACKVIS_RETURN_IF_ERROR(timeFetch(*connections, report, timed));
    }
    if (!timed) {
      continue;
    }
    report.rounds.push_back(lastRound(report));
    report.settled = settled(report.rounds, options.settle);
    if (round + 1 >= options.repeat && report.settled) {
      break;
    }
  }
  report.loadAfter = loadAverage();
  return report;
}

nlohmann::json toJson(const Report& report, const TransferOptions& options) {
  auto timing = [](const Timing& t) {
    return nlohmann::json{{"bytes", t.bytes},
                          {"wire_bytes", t.wireBytes},
                          {"seconds_median", t.median()},
                          {"seconds_best", t.best()},
                          {"seconds_all", t.seconds},
                          {"mb_per_s", t.megabytesPerSecond()}};
  };
  if (options.viewsOnly) {
    return {{"file", report.file},
            {"step", report.step},
            {"warm_step", report.warmStep},
            {"server", report.server},
            {"views_only", true},
            {"runs", report.firstView.seconds.size()},
            {"machine", machineDescription()},
            {"load_before", toJson(report.loadBefore)},
            {"load_after", toJson(report.loadAfter)},
            {"describe",
             {{"held_answer", true},
              {"seconds_median", report.describe.median()},
              {"seconds_all", report.describe.seconds}}},
            {"grpc_cold_first_view", timing(report.coldFirstView)},
            {"grpc_first_view", timing(report.firstView)},
            {"grpc_first_view_raw_chunks", timing(report.rawChunksFirstView)},
            {"grpc_warm_view", timing(report.warmView)}};
  }
  const auto ratios = medianRatios(report.rounds, report.rounds.size());
  return {
      {"file", report.file},
      {"step", report.step},
      {"warm_step", report.warmStep},
      {"server", report.server},
      {"raw_tls", report.raw},
      {"raw_tls_session", report.tls},
      {"runs", report.rounds.size()},
      {"settled", report.settled},
      {"settle_tolerance", options.settle},
      {"machine", machineDescription()},
      {"load_before", toJson(report.loadBefore)},
      {"load_after", toJson(report.loadAfter)},
      {"describe",
       {{"round_trips", 1},
        {"held_answer", true},
        {"seconds_median", report.describe.median()},
        {"seconds_all", report.describe.seconds}}},
      {"describe_cold",
       {{"round_trips", 1},
        {"seconds_median", report.coldDescribe.median()},
        {"seconds_all", report.coldDescribe.seconds}}},
      {"grpc_cold_first_view", timing(report.coldFirstView)},
      {"grpc_fetch_full", timing(report.fetch)},
      {"grpc_first_view", timing(report.firstView)},
      {"grpc_first_view_raw_chunks", timing(report.rawChunksFirstView)},
      {"grpc_warm_view", timing(report.warmView)},
      {"raw_tls_full", timing(report.rawFull)},
      {"raw_tls_view", timing(report.rawView)},
      {"ratios",
       {{"bytes_full_over_first_view",
         report.firstView.bytes > 0
             ? static_cast<double>(report.fetch.bytes) / static_cast<double>(report.firstView.bytes)
             : 0.0},
        {"bytes_full_over_first_view_wire",
         report.firstView.wireBytes > 0 ? static_cast<double>(report.fetch.bytes) /
                                              static_cast<double>(report.firstView.wireBytes)
                                        : 0.0},
        {"time_full_fetch_over_first_view", ratios[0]},
        {"time_full_fetch_over_cold_first_view", ratios[1]},
        {"time_full_fetch_over_warm_view", ratios[2]},
        {"time_full_fetch_over_first_view_raw_chunks", ratios[4]},
        {"grpc_over_raw_tls_throughput_full", ratios[3]},
        {"grpc_over_raw_tls_throughput_first_view", ratios[5]}}},
      {"goals",
       {{"time_full_fetch_over_first_view", 100.0},
        {"time_full_fetch_over_warm_view", 150.0},
        {"grpc_over_raw_tls_throughput_full", 0.70},
        {"met", ratios[0] >= 100.0 && ratios[2] >= 150.0 && ratios[3] >= 0.70}}},
  };
}

void printViews(const Report& report, const nlohmann::json& json) {
  fmt::print("crackvis bench transfer --views-only: {} step {} (then step {}) from {}\n",
             report.file, report.step, report.warmStep, report.server);
  fmt::print("machine: {}; load before {}, after {}\n", json.at("machine").get<std::string>(),
             loadText(json.at("load_before")), loadText(json.at("load_after")));
  fmt::print("medians of {} rounds after one warm-up; MB = 10^6 bytes\n\n",
             report.firstView.seconds.size());
  fmt::print("{:<44} {:>11} {:>11} {:>10} {:>8}\n", "transfer", "bytes", "wire bytes", "seconds",
             "MB/s");
  auto row = [](const std::string& name, const Timing& t) {
    fmt::print("{:<44} {:>11} {:>11} {:>10.6f} {:>8.1f}\n", name, t.bytes, t.wireBytes, t.median(),
               t.megabytesPerSecond());
  };
  row(fmt::format("(b) first view of step {}: Describe + Read", report.step), report.firstView);
  row("(b) the same, every chunk raw (not packed)", report.rawChunksFirstView);
  row("(b') cold first view: walked Describe + Read", report.coldFirstView);
  row(fmt::format("(c) warm view: step {}, one Read", report.warmStep), report.warmView);
  fmt::print("\n");
}

void printTable(const Report& report, const nlohmann::json& json) {
  if (json.value("views_only", false)) {
    printViews(report, json);
    return;
  }
  fmt::print("crackvis bench transfer: {} step {} (then step {}) from {} (raw TLS {}, {})\n",
             report.file, report.step, report.warmStep, report.server, report.raw, report.tls);
  fmt::print("machine: {}; load before {}, after {}\n", json.at("machine").get<std::string>(),
             loadText(json.at("load_before")), loadText(json.at("load_after")));
  fmt::print(
      "medians of {} alternating rounds after one warm-up ({}); ratios: the median of each "
      "round's ratio; MB = 10^6 bytes\n\n",
      report.rounds.size(),
      report.settled
          ? "settled: the last two rounds moved no median ratio by more than " +
                fmt::format("{:.0f} %", 100.0 * json.at("settle_tolerance").get<double>())
          : "NOT settled within --max-repeat");
  fmt::print("{:<44} {:>11} {:>11} {:>10} {:>8}\n", "transfer", "bytes", "wire bytes", "seconds",
             "MB/s");
  auto row = [](const std::string& name, const Timing& t) {
    fmt::print("{:<44} {:>11} {:>11} {:>10.6f} {:>8.1f}\n", name, t.bytes, t.wireBytes, t.median(),
               t.megabytesPerSecond());
  };
  row("(a) full file, gRPC Fetch", report.fetch);
  row(fmt::format("(b) first view of step {}: Describe + Read", report.step), report.firstView);
  fmt::print("{:<44} {:>11} {:>11} {:>10.6f} {:>8}\n", "    of which Describe (held answer)", "-",
             "-", report.describe.median(), "-");
  row("(b) the same, every chunk raw (not packed)", report.rawChunksFirstView);
  row("(b') cold first view: walked Describe + Read", report.coldFirstView);
  fmt::print("{:<44} {:>11} {:>11} {:>10.6f} {:>8}\n", "    of which Describe (file walked)", "-",
             "-", report.coldDescribe.median(), "-");
  row(fmt::format("(c) warm view: step {}, one Read", report.warmStep), report.warmView);
  row("(d) full file bytes, raw TLS", report.rawFull);
  row("(d) first view's wire bytes, raw TLS", report.rawView);
  const auto& ratios = json.at("ratios");
  fmt::print("\nratios\n");
  fmt::print("  bytes, full file / first view             {:>9.1f}\n",
             ratios.at("bytes_full_over_first_view").get<double>());
  fmt::print("  bytes, full file / first view's wire bytes {:>8.1f}\n",
             ratios.at("bytes_full_over_first_view_wire").get<double>());
  fmt::print("  time, full Fetch / first view             {:>9.1f}x  (goal >= 100x)\n",
             ratios.at("time_full_fetch_over_first_view").get<double>());
  fmt::print("  time, full Fetch / first view, raw chunks  {:>9.1f}x\n",
             ratios.at("time_full_fetch_over_first_view_raw_chunks").get<double>());
  fmt::print("  time, full Fetch / cold first view        {:>9.1f}x\n",
             ratios.at("time_full_fetch_over_cold_first_view").get<double>());
  fmt::print("  time, full Fetch / warm view              {:>9.1f}x  (goal >= 150x)\n",
             ratios.at("time_full_fetch_over_warm_view").get<double>());
  fmt::print("  throughput, gRPC / raw TLS, full file     {:>9.2f}   (goal >= 0.70)\n",
             ratios.at("grpc_over_raw_tls_throughput_full").get<double>());
  fmt::print("  throughput, gRPC / raw TLS, first view    {:>9.2f}   (its wire bytes)\n",
             ratios.at("grpc_over_raw_tls_throughput_first_view").get<double>());
  fmt::print("goals: {}\n\n", json.at("goals").at("met").get<bool>() ? "met" : "NOT met");
}

int runTransfer(const TransferOptions& options) {
  if (!options.viewsOnly && options.raw.empty()) {
    // A usage error, as CLI11 reports a missing required option.
    printError("bench transfer", "--raw is required (the raw TLS baseline), unless --views-only");
    return kExitUsage;
  }
  auto report = measure(options);
  if (!report) {
    printError("bench transfer", report.status().message());
    return kExitFailure;
  }
  const nlohmann::json json = toJson(*report, options);
  if (!options.jsonOnly) {
    printTable(*report, json);
  }
  std::printf("%s\n", json.dump(2).c_str());
  return kExitOk;
}

}  // namespace

Command addBenchTransferCommand(CLI::App& bench) {
  auto options = std::make_shared<TransferOptions>();
  auto* command = bench.add_subcommand(
      "transfer",
      "Time, in one run against a running crackvis-data: (a) the whole file through Fetch, "
      "(b) a view's first step from nothing: Describe, then the Read of step K's positions and "
      "bond states with the bond list, also with every chunk raw (integer arrays not packed), (c) "
      "a step change on that view (one Read of the step "
      "before), (d) the whole file and the first view's wire bytes over a raw TLS socket with the "
      "same certificates "
      "(crackvis-data --raw-tls-listen). Rounds alternate their order and repeat until the "
      "median ratios settle. Prints bytes, seconds, MB/s, ratios and the load as a table and as "
      "JSON. Certificates come from certs/make-dev-certs.sh; --ca, --cert and --key name them "
      "(defaults: certs/generated/ca.pem, client.pem, client.key, or where they are missing "
      "/etc/crackvis/certs).");
  command->add_option("--server", options->server, "crackvis-data address, HOST:PORT")->required();
  command
      ->add_option("--file", options->file, "crackvis-dem file, relative to the server's data root")
      ->required();
  command->add_option("--step", options->step, "step the view shows (default: the last)");
  command->add_option("--raw", options->raw,
                      "raw TLS baseline address, HOST:PORT: crackvis-data's --raw-tls-listen "
                      "(required unless --views-only)");
  command->add_option("--ca", options->tls.ca, "CA certificate that signed the server's (PEM)")
      ->capture_default_str();
  command->add_option("--cert", options->tls.cert, "client certificate (PEM)")
      ->capture_default_str();
  command->add_option("--key", options->tls.key, "client private key (PEM)")->capture_default_str();
  command->add_option("--token", options->token, "bearer token, when the server has users");
  command
      ->add_option("--repeat", options->repeat,
                   "fewest timed rounds; more run until the median ratios settle")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  command->add_option("--max-repeat", options->maxRepeat, "most timed rounds")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  command
      ->add_option("--settle", options->settle,
                   "settled: the last two rounds moved no median ratio by more than this "
                   "fraction")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command->add_flag("--views-only", options->viewsOnly,
                    "time only the views (b, c), --repeat alternating rounds: no Fetch, no "
                    "raw TLS, no ratios; for files too large to fetch whole in a benchmark");
  command->add_flag("--json", options->jsonOnly, "print only the JSON");
  return {command, [options] { return runTransfer(*options); }};
}

}  // namespace crackvis::cli
