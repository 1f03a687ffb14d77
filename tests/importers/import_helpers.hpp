// Shared by the importer tests: read what an import wrote, and read the
// codes' own text files independently of the importers.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include <crackvis/dem/dem_file.hpp>
#include <crackvis/importers/importer.hpp>

namespace crackvis::testing {

inline const std::string kTestData = CRACKVIS_TEST_DATA;

inline importers::ImportOptions quietImport(const std::string& output) {
  importers::ImportOptions options;
  options.output = output;
  options.progress = false;
  options.invocation = "test";
  return options;
}

// A whitespace table with a '#' header: column name -> values by row.
inline std::map<std::string, std::vector<double>> readTable(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> names;
  std::map<std::string, std::vector<double>> table;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    if (names.empty()) {
      std::string name;
      while (words >> name) {
        if (name != "#") {
          names.push_back(name);
        }
      }
      continue;
    }
    for (const std::string& name : names) {
      double value = 0.0;
      words >> value;
      table[name].push_back(value);
    }
  }
  return table;
}

inline double scalarOf(const dem::StepInfo& step, const std::string& name) {
  for (const auto& scalar : step.scalars) {
    if (scalar.name == name) {
      return scalar.value;
    }
  }
  FAIL("step " << step.index << " has no scalar " << name);
  return 0.0;
}

}  // namespace crackvis::testing
