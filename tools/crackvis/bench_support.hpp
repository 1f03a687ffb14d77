// What every `crackvis bench` prints beside its figures: the machine, its
// load while the benchmark ran, and order statistics of repeated runs.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace crackvis::cli {

// The 1-, 5- and 15-minute load averages (getloadavg; zeros where
// unavailable). On a shared machine `nice` does not yield the CPU
// (sched_autogroup), so a figure is only as good as the load beside it.
struct LoadAverage {
  double one = 0.0;
  double five = 0.0;
  double fifteen = 0.0;
};
LoadAverage loadAverage();
std::string toString(const LoadAverage& load);
nlohmann::json toJson(const LoadAverage& load);
// "1.00 0.50 0.25" from toJson's array.
std::string loadText(const nlohmann::json& load);

// "CPU model, N hardware threads" from /proc/cpuinfo.
std::string machineDescription();

// The p-th percentile (0..100) with linear interpolation; 0 for no values.
double percentile(std::vector<double> values, double p);
inline double median(std::vector<double> values) {
  return percentile(std::move(values), 50.0);
}
double mean(const std::vector<double>& values);

// {count, mean, p50, p90, p99} for a JSON report.
nlohmann::json summaryJson(const std::vector<double>& values);

}  // namespace crackvis::cli
