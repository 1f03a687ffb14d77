#include "scalar_table.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "text_input.hpp"

namespace crackvis::importers {
namespace {

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

}  // namespace

Result<ScalarTable> ScalarTable::read(const std::string& path) {
  auto input = TextInput::open(path);
  if (!input) {
    return input.status();
  }
  std::string line;
  std::vector<std::string_view> header;
  std::string headerLine;
  while (input->next(line)) {
    std::string_view text(line);
    while (!text.empty() && (text.front() == '#' || text.front() == ' ')) {
      text.remove_prefix(1);
    }
    if (!text.empty()) {
      headerLine = std::string(text);
      header = splitFields(headerLine);
      break;
    }
  }
  if (header.empty()) {
    return input->error("empty table: expected a header line of column names");
  }
  int stepColumn = -1;
  for (std::size_t c = 0; c < header.size(); ++c) {
    const std::string name = lower(header[c]);
    if (stepColumn < 0 &&
        (name == "step" || name == "timestep" || name == "iter" || name == "iteration")) {
      stepColumn = static_cast<int>(c);
    }
  }
  if (stepColumn < 0) {
    return input->error(fmt::format(
        "no step column in the header '{}' (name one column step, timestep, iter or iteration)",
        headerLine));
  }
  ScalarTable table;
  std::vector<bool> numeric;  // decided by the first data row
  while (input->next(line)) {
    if (line.empty() || line.front() == '#') {
      continue;
    }
    const auto fields = splitFields(line);
    if (fields.empty()) {
      continue;
    }
    if (fields.size() != header.size()) {
      return input->error(fmt::format("{} values for {} columns", fields.size(), header.size()));
    }
    std::int64_t step = 0;
    if (!parseId(fields[static_cast<std::size_t>(stepColumn)], step)) {
      return input->error(
          fmt::format("step '{}' is not an integer", fields[static_cast<std::size_t>(stepColumn)]));
    }
    if (numeric.empty()) {
      for (std::size_t c = 0; c < fields.size(); ++c) {
        double value = 0.0;
        numeric.push_back(static_cast<int>(c) == stepColumn || parseNumber(fields[c], value));
        if (static_cast<int>(c) == stepColumn) {
          continue;
        }
        (numeric.back() ? table.m_names : table.m_textColumns).push_back(safeName(header[c]));
      }
    }
    std::vector<double> values;
    for (std::size_t c = 0; c < fields.size(); ++c) {
      if (static_cast<int>(c) == stepColumn || !numeric[c]) {
        continue;
      }
      double value = 0.0;
      if (!parseNumber(fields[c], value)) {
        return input->error(fmt::format("column {} ({}): '{}' is not a number", c + 1,
                                        safeName(header[c]), fields[c]));
      }
      values.push_back(value);
    }
    table.m_rows[step] = std::move(values);
  }
  return table;
}

std::optional<double> ScalarTable::fittedTime(std::int64_t sourceStep) const {
  const auto column = std::find(m_names.begin(), m_names.end(), "time");
  if (column == m_names.end()) {
    return std::nullopt;
  }
  const auto c = static_cast<std::size_t>(column - m_names.begin());
  double n = 0;
  double sx = 0;
  double sy = 0;
  double sxx = 0;
  double sxy = 0;
  for (const auto& [step, values] : m_rows) {
    if (!std::isfinite(values[c])) {
      continue;
    }
    const auto x = static_cast<double>(step);
    n += 1;
    sx += x;
    sy += values[c];
    sxx += x * x;
    sxy += x * values[c];
  }
  const double spread = n * sxx - sx * sx;
  if (n < 2 || !(spread > 0.0)) {
    return std::nullopt;
  }
  const double slope = (n * sxy - sx * sy) / spread;
  return (sy - slope * sx) / n + slope * static_cast<double>(sourceStep);
}

std::vector<dem::StepScalar> ScalarTable::at(std::int64_t sourceStep) const {
  std::vector<dem::StepScalar> scalars;
  const auto row = m_rows.find(sourceStep);
  if (row == m_rows.end()) {
    return scalars;
  }
  for (std::size_t c = 0; c < m_names.size(); ++c) {
    if (std::isfinite(row->second[c])) {
      scalars.push_back({m_names[c], row->second[c]});
    }
  }
  return scalars;
}

}  // namespace crackvis::importers
