// crackvis bench transfer against a real server with the raw TLS baseline
// on: one run prints the table and JSON whose byte counts are the file's
// and the view's.
#include <filesystem>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "dataservice/service_fixture.hpp"
#include "support/process.hpp"

namespace crackvis::testing {
namespace {

TEST_CASE("crackvis bench transfer measures Fetch, a first and a warm view, and raw TLS",
          "[dataservice][integration][bench]") {
  auto config = baseConfig();
  config.rawTlsListen = "127.0.0.1:0";
  auto server = startServer(config);
  REQUIRE(server->rawTlsPort() != 0);
  const auto tls = clientTls();
  const std::vector<std::string> common = {CRACKVIS_CLI,
                                           "bench",
                                           "transfer",
                                           "--server",
                                           server->address(),
                                           "--raw",
                                           fmt::format("127.0.0.1:{}", server->rawTlsPort()),
                                           "--file",
                                           "run.h5",
                                           "--step",
                                           "1",
                                           "--repeat",
                                           "3",
                                           "--max-repeat",
                                           "4",
                                           "--ca",
                                           tls.ca,
                                           "--cert",
                                           tls.cert,
                                           "--key",
                                           tls.key};

  const ProcessResult table = runProcess(common);
  INFO(table.err);
  REQUIRE(table.exitCode == 0);
  CHECK_THAT(table.out, Catch::Contains("(a) full file, gRPC Fetch") &&
                            Catch::Contains("(b) first view of step 1: Describe + Read") &&
                            Catch::Contains("(c) warm view: step 0, one Read") &&
                            Catch::Contains("raw TLS") && Catch::Contains("goal >= 100x") &&
                            Catch::Contains("load before"));

  std::vector<std::string> jsonArgs = common;
  jsonArgs.push_back("--json");
  const ProcessResult json = runProcess(jsonArgs);
  INFO(json.err);
  REQUIRE(json.exitCode == 0);
  const auto report = nlohmann::json::parse(json.out);
  const SampleData& sample = sampleRoot().sample3d;
  const std::uint64_t viewBytes =
      sample.lattice.particleCount() * 24 + sample.lattice.bondCount() * (1 + 8);
  CHECK(report.at("step") == 1);
  CHECK(report.at("grpc_fetch_full").at("bytes") ==
        std::filesystem::file_size(sampleRoot().file("run.h5")));
  CHECK(report.at("raw_tls_full").at("bytes") == report.at("grpc_fetch_full").at("bytes"));
  CHECK(report.at("grpc_first_view").at("bytes") == viewBytes);
  // The bond list and bond states travel packed; raw TLS moves as many bytes.
  const auto wireBytes = report.at("grpc_first_view").at("wire_bytes").get<std::uint64_t>();
  CHECK(wireBytes < viewBytes - sample.lattice.bondCount() * 4);
  CHECK(wireBytes > sample.lattice.particleCount() * 24);
  CHECK(report.at("raw_tls_view").at("bytes") == wireBytes);
  // The same view with every chunk raw moves every byte.
  CHECK(report.at("grpc_first_view_raw_chunks").at("bytes") == viewBytes);
  CHECK(report.at("grpc_first_view_raw_chunks").at("wire_bytes") == viewBytes);
  // A step change moves the step's positions and bond states only.
  CHECK(report.at("warm_step") == 0);
  CHECK(report.at("grpc_warm_view").at("bytes") ==
        sample.lattice.particleCount() * 24 + sample.lattice.bondCount());
  // At least --repeat rounds, at most --max-repeat, every timing once per round.
  const std::size_t runs = report.at("runs").get<std::size_t>();
  CHECK(runs >= 3);
  CHECK(runs <= 4);
  CHECK(report.at("settled").is_boolean());
  CHECK(report.at("grpc_first_view").at("seconds_all").size() == runs);
  CHECK(report.at("grpc_warm_view").at("seconds_all").size() == runs);
  CHECK(report.at("grpc_first_view_raw_chunks").at("seconds_all").size() == runs);
  CHECK(report.at("describe").at("seconds_all").size() == runs);
  CHECK(report.at("describe").at("round_trips") == 1);
  // The first view includes its Describe and so takes longer than a step change.
  CHECK(report.at("describe").at("seconds_median").get<double>() <
        report.at("grpc_first_view").at("seconds_median").get<double>());
  const auto& ratios = report.at("ratios");
  CHECK(ratios.at("time_full_fetch_over_first_view").get<double>() > 0.0);
  CHECK(ratios.at("time_full_fetch_over_warm_view").get<double>() > 0.0);
  CHECK(ratios.at("time_full_fetch_over_first_view_raw_chunks").get<double>() > 0.0);
  CHECK(ratios.at("grpc_over_raw_tls_throughput_first_view").get<double>() > 0.0);
  CHECK(ratios.at("bytes_full_over_first_view_wire").get<double>() >
        ratios.at("bytes_full_over_first_view").get<double>());
  CHECK(ratios.at("grpc_over_raw_tls_throughput_full").get<double>() > 0.0);
  CHECK(report.at("load_before").size() == 3);
  CHECK(report.at("goals").at("met").is_boolean());

  SECTION("--views-only: the view reads alone, --repeat rounds, no Fetch and no --raw") {
    std::vector<std::string> args = {common.begin(), common.begin() + 5};
    args.insert(args.end(), common.begin() + 7, common.end());  // without --raw
    args.insert(args.end(), {"--views-only", "--json"});
    const ProcessResult views = runProcess(args);
    INFO(views.err);
    REQUIRE(views.exitCode == 0);
    const auto only = nlohmann::json::parse(views.out);
    CHECK(only.at("views_only") == true);
    CHECK(only.at("runs") == 3);
    CHECK(only.at("grpc_first_view").at("bytes") == viewBytes);
    CHECK(only.at("grpc_warm_view").at("seconds_all").size() == 3);
    CHECK(only.at("grpc_first_view_raw_chunks").at("seconds_all").size() == 3);
    CHECK(only.at("grpc_first_view_raw_chunks").at("wire_bytes") == viewBytes);
    CHECK(only.at("grpc_warm_view").at("seconds_median").get<double>() > 0.0);
    CHECK_FALSE(only.contains("grpc_fetch_full"));
    CHECK_FALSE(only.contains("ratios"));
    args.pop_back();
    args.pop_back();
    const ProcessResult noRaw = runProcess(args);  // neither --raw nor --views-only
    CHECK(noRaw.exitCode == 2);                    // a usage error
    CHECK_THAT(noRaw.err, Catch::Contains("--raw is required"));
  }
  SECTION("without the raw TLS baseline: one clear line") {
    std::vector<std::string> args = common;
    args[6] = "127.0.0.1:1";  // --raw: nothing listens there
    const ProcessResult failed = runProcess(args);
    CHECK(failed.exitCode == 1);
    CHECK(lines(failed.err).size() == 1);
    CHECK_THAT(failed.err, Catch::StartsWith("crackvis bench transfer: raw TLS baseline"));
  }
}

}  // namespace
}  // namespace crackvis::testing
