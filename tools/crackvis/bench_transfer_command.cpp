// crackvis bench transfer: what partial reads save, measured in one run
// against a running crackvis-data. Times (a) the whole file through Fetch,
// (b) the Read a view of step K needs (positions and bond states of K, plus
// the bond list once), and (c) the same byte counts over a raw TLS socket
// with the same certificates (crackvis-data --raw-tls-listen), the physical
// baseline of the link; prints bytes, seconds, MB/s and the ratios as a
// table and as JSON.
#include <algorithm>
#include <chrono>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include <crackvis/dataservice/data_client.hpp>
#include <crackvis/dataservice/raw_tls_client.hpp>
#include <crackvis/dataservice/remote_dem_file.hpp>

namespace crackvis::cli {
namespace {

using Clock = std::chrono::steady_clock;
namespace ds = crackvis::dataservice;

struct TransferOptions {
  std::string server;
  std::string raw;
  std::string file;
  int step = -1;
  std::string ca = "certs/generated/ca.pem";
  std::string cert = "certs/generated/client.pem";
  std::string key = "certs/generated/client.key";
  std::string token;
  int repeat = 3;
  bool jsonOnly = false;
};

struct Timing {
  std::string name;
  std::uint64_t bytes = 0;
  std::vector<double> seconds;

  double median() const {
    std::vector<double> sorted = seconds;
    std::sort(sorted.begin(), sorted.end());
    const size_t n = sorted.size();
    return n == 0 ? 0.0 : (n % 2 == 1 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]));
  }
  double best() const { return *std::min_element(seconds.begin(), seconds.end()); }
  double megabytesPerSecond() const {
    return median() > 0.0 ? static_cast<double>(bytes) / 1e6 / median() : 0.0;
  }
};

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// "host:port" -> "host:port+1", the default raw TLS address.
Result<std::string> nextPort(const std::string& address) {
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos) {
    return invalidArgument(fmt::format("--server '{}': expected HOST:PORT", address));
  }
  try {
    return fmt::format("{}:{}", address.substr(0, colon), std::stoi(address.substr(colon + 1)) + 1);
  } catch (const std::exception&) {
    return invalidArgument(fmt::format("--server '{}': expected HOST:PORT", address));
  }
}

struct Report {
  std::string file;
  int step = 0;
  std::string server;
  std::string raw;
  std::string tls;
  int repeat = 0;
  Timing describe;
  Timing fetch;
  Timing view;
  Timing rawFull;
  Timing rawView;
};

Result<Report> measure(const TransferOptions& options) {
  Report report;
  report.file = options.file;
  report.server = options.server;
  report.repeat = options.repeat;
  if (options.raw.empty()) {
    auto raw = nextPort(options.server);
    if (!raw) {
      return raw.status();
    }
    report.raw = *raw;
  } else {
    report.raw = options.raw;
  }
  ds::ClientOptions clientOptions;
  clientOptions.target = options.server;
  clientOptions.tls = {options.ca, options.cert, options.key};
  clientOptions.token = options.token;
  clientOptions.timeoutSeconds = 3600.0;
  auto client = ds::DataClient::connect(clientOptions);
  if (!client) {
    return client.status();
  }
  CRACKVIS_RETURN_IF_ERROR(client->checkHealth());  // connects: no handshake in the timings
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
  ds::RawTlsOptions raw;
  raw.target = report.raw;
  raw.tls = clientOptions.tls;
  if (!options.token.empty()) {
    raw.authorization = "Bearer " + options.token;
  }

  report.describe.name = "describe";
  report.fetch.name = "fetch";
  report.view.name = "view";
  report.rawFull.name = "raw_full";
  report.rawView.name = "raw_view";
  // One untimed round of everything first: the page cache and the
  // connections are warm for every timed round alike.
  for (int round = -1; round < options.repeat; ++round) {
    const bool timed = round >= 0;
    auto start = Clock::now();
    auto description = client->describe(options.file);
    if (!description) {
      return description.status();
    }
    if (timed) {
      report.describe.seconds.push_back(since(start));
    }

    start = Clock::now();
    auto fetched = client->fetch(options.file, {});
    if (!fetched) {
      return fetched.status();
    }
    if (timed) {
      report.fetch.seconds.push_back(since(start));
    }
    report.fetch.bytes = *fetched;

    // A fresh file each round, so the bond list travels every time.
    auto view = ds::RemoteDemFile::open(*client, options.file);
    if (!view) {
      return view.status();
    }
    start = Clock::now();
    auto step = view->readStep(report.step);
    if (!step) {
      return step.status();
    }
    if (timed) {
      report.view.seconds.push_back(since(start));
    }
    report.view.bytes = step->positions.size() * sizeof(dem::Vec3) + step->bondState.size() +
                        (*view->bonds())->size() * sizeof(dem::Bond);

    auto rawFull = ds::rawTlsRead(raw, options.file, 0, 0);
    if (!rawFull) {
      return Status(rawFull.status().code(),
                    fmt::format("raw TLS baseline at {} (start crackvis-data with "
                                "--raw-tls-listen, or give --raw): {}",
                                report.raw, rawFull.status().message()));
    }
    auto rawView = ds::rawTlsRead(raw, options.file, 0, report.view.bytes);
    if (!rawView) {
      return rawView.status();
    }
    if (timed) {
      report.rawFull.seconds.push_back(rawFull->transferSeconds);
      report.rawView.seconds.push_back(rawView->transferSeconds);
    }
    report.rawFull.bytes = rawFull->bytes;
    report.rawView.bytes = rawView->bytes;
    report.tls = rawFull->protocol + " " + rawFull->cipher;
    report.describe.bytes = 0;
  }
  return report;
}

nlohmann::json toJson(const Report& report) {
  auto timing = [](const Timing& t) {
    return nlohmann::json{{"bytes", t.bytes},
                          {"seconds_median", t.median()},
                          {"seconds_best", t.best()},
                          {"seconds_all", t.seconds},
                          {"mb_per_s", t.megabytesPerSecond()}};
  };
  const double speedup =
      report.view.median() > 0 ? report.fetch.median() / report.view.median() : 0;
  return {
      {"file", report.file},
      {"step", report.step},
      {"server", report.server},
      {"raw_tls", report.raw},
      {"raw_tls_session", report.tls},
      {"runs", report.repeat},
      {"describe",
       {{"round_trips", 1},
        {"seconds_median", report.describe.median()},
        {"seconds_all", report.describe.seconds}}},
      {"grpc_fetch_full", timing(report.fetch)},
      {"grpc_read_view", timing(report.view)},
      {"raw_tls_full", timing(report.rawFull)},
      {"raw_tls_view", timing(report.rawView)},
      {"ratios",
       {{"bytes_full_over_view", report.view.bytes > 0 ? static_cast<double>(report.fetch.bytes) /
                                                             static_cast<double>(report.view.bytes)
                                                       : 0.0},
        {"time_full_fetch_over_view_read", speedup},
        {"grpc_over_raw_tls_throughput_full",
         report.rawFull.megabytesPerSecond() > 0
             ? report.fetch.megabytesPerSecond() / report.rawFull.megabytesPerSecond()
             : 0.0},
        {"grpc_over_raw_tls_throughput_view",
         report.rawView.megabytesPerSecond() > 0
             ? report.view.megabytesPerSecond() / report.rawView.megabytesPerSecond()
             : 0.0}}},
      {"targets",
       {{"time_full_fetch_over_view_read", ">= 100"},
        {"grpc_over_raw_tls_throughput_full", ">= 0.70"},
        {"describe_round_trips", 1}}},
  };
}

void printTable(const Report& report, const nlohmann::json& json) {
  fmt::print("crackvis bench transfer: {} step {} from {} (raw TLS {}, {})\n", report.file,
             report.step, report.server, report.raw, report.tls);
  fmt::print("median of {} runs after one warm-up; MB = 10^6 bytes\n\n", report.repeat);
  fmt::print("{:<34} {:>14} {:>11} {:>10}\n", "transfer", "bytes", "seconds", "MB/s");
  fmt::print("{:<34} {:>14} {:>11.6f} {:>10}\n", "Describe (1 round trip)", "-",
             report.describe.median(), "-");
  auto row = [](const std::string& name, const Timing& t) {
    fmt::print("{:<34} {:>14} {:>11.6f} {:>10.1f}\n", name, t.bytes, t.median(),
               t.megabytesPerSecond());
  };
  row("(a) full file, gRPC Fetch", report.fetch);
  row(fmt::format("(b) view of step {}, gRPC Read", report.step), report.view);
  row("(c) full file bytes, raw TLS", report.rawFull);
  row("(c) view bytes, raw TLS", report.rawView);
  const auto& ratios = json.at("ratios");
  fmt::print("\nratios\n");
  fmt::print("  bytes, full file / view                 {:>9.1f}\n",
             ratios.at("bytes_full_over_view").get<double>());
  fmt::print("  time, full Fetch / view Read            {:>9.1f}x  (target >= 100x)\n",
             ratios.at("time_full_fetch_over_view_read").get<double>());
  fmt::print("  throughput, gRPC / raw TLS, full file   {:>9.2f}   (target >= 0.70)\n",
             ratios.at("grpc_over_raw_tls_throughput_full").get<double>());
  fmt::print("  throughput, gRPC / raw TLS, view        {:>9.2f}\n\n",
             ratios.at("grpc_over_raw_tls_throughput_view").get<double>());
}

int runTransfer(const TransferOptions& options) {
  auto report = measure(options);
  if (!report) {
    printError("bench transfer", report.status().message());
    return kExitFailure;
  }
  const nlohmann::json json = toJson(*report);
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
      "(b) the partial Read a view of step K needs (positions and bond states of K, plus the "
      "bond list), (c) the same byte counts over a raw TLS socket with the same certificates "
      "(crackvis-data --raw-tls-listen). Prints bytes, seconds, MB/s and ratios as a table and "
      "as JSON. Certificates come from certs/make-dev-certs.sh; --ca, --cert and --key name "
      "them (defaults: certs/generated/ca.pem, client.pem, client.key).");
  command->add_option("--server", options->server, "crackvis-data address, HOST:PORT")->required();
  command
      ->add_option("--file", options->file, "crackvis-dem file, relative to the server's data root")
      ->required();
  command->add_option("--step", options->step, "step the view shows (default: the last)");
  command->add_option("--raw", options->raw,
                      "raw TLS baseline address, HOST:PORT (default: the server's port + 1)");
  command->add_option("--ca", options->ca, "CA certificate that signed the server's (PEM)")
      ->capture_default_str();
  command->add_option("--cert", options->cert, "client certificate (PEM)")->capture_default_str();
  command->add_option("--key", options->key, "client private key (PEM)")->capture_default_str();
  command->add_option("--token", options->token, "bearer token, when the server has users");
  command->add_option("--repeat", options->repeat, "timed runs; the median is reported")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  command->add_flag("--json", options->jsonOnly, "print only the JSON");
  return {command, [options] { return runTransfer(*options); }};
}

}  // namespace crackvis::cli
