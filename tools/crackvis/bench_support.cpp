#include "bench_support.hpp"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <thread>

#include <fmt/format.h>

namespace crackvis::cli {

LoadAverage loadAverage() {
  double values[3] = {0.0, 0.0, 0.0};
  if (getloadavg(values, 3) != 3) {
    return {};
  }
  return {values[0], values[1], values[2]};
}

std::string toString(const LoadAverage& load) {
  return fmt::format("{:.2f} {:.2f} {:.2f}", load.one, load.five, load.fifteen);
}

nlohmann::json toJson(const LoadAverage& load) {
  return nlohmann::json::array({load.one, load.five, load.fifteen});
}

std::string loadText(const nlohmann::json& load) {
  return fmt::format("{:.2f} {:.2f} {:.2f}", load.at(0).get<double>(), load.at(1).get<double>(),
                     load.at(2).get<double>());
}

std::string machineDescription() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  std::string model = "unknown CPU";
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) {
        model = line.substr(line.find_first_not_of(' ', colon + 1));
      }
      break;
    }
  }
  return fmt::format("{}, {} hardware threads", model, std::thread::hardware_concurrency());
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) {
    return 0.0;
  }
  std::sort(values.begin(), values.end());
  const double at = p / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(at);
  const auto hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (values[hi] - values[lo]) * (at - static_cast<double>(lo));
}

double mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) {
    sum += v;
  }
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

nlohmann::json summaryJson(const std::vector<double>& values) {
  return {{"count", values.size()},        {"mean", mean(values)},
          {"p50", percentile(values, 50)}, {"p90", percentile(values, 90)},
          {"p95", percentile(values, 95)}, {"p99", percentile(values, 99)}};
}

}  // namespace crackvis::cli
