#include "support/dem_defects.hpp"

#include <cmath>
#include <fstream>
#include <limits>

#include <fmt/format.h>

#include "support/h5_tamper.hpp"

namespace crackvis::testing {

std::vector<DemDefect> demDefects(const SampleData& sample) {
  using dem::h5::ElementType;
  auto n = [](const SampleData& s) {
    return static_cast<std::uint64_t>(s.lattice.particleCount());
  };
  auto m = [](const SampleData& s) { return static_cast<std::uint64_t>(s.lattice.bondCount()); };
  const std::uint64_t particles = n(sample);
  const std::uint64_t bonds = m(sample);
  return {
      {"not an HDF5 file",
       [](const std::string& path, const SampleData&) {
         std::ofstream(path, std::ios::trunc) << "step,x,y,z\n0,1,2,3\n";
       },
       {"not an HDF5 file"}},
      {"wrong format attribute",
       [](const std::string& path, const SampleData&) {
         setStringAttribute(path, "/", "format", "vtkhdf");
       },
       {"not a crackvis-dem file", "'format' is 'vtkhdf'"}},
      {"missing format attribute",
       [](const std::string& path, const SampleData&) { deleteAttribute(path, "/", "format"); },
       {"not a crackvis-dem file", "missing attribute 'format'"}},
      {"wrong version",
       [](const std::string& path, const SampleData&) { setIntAttribute(path, "/", "version", 7); },
       {"unsupported crackvis-dem version 7", "reads version 1"}},
      {"missing dataset",
       [](const std::string& path, const SampleData&) { deleteLink(path, "/bonds/break_step"); },
       {"missing dataset /bonds/break_step"}},
      {"v1.0 file without strengths",
       [](const std::string& path, const SampleData&) {
         deleteAttribute(path, "/", "version_minor");  // strengths were required before v1.1
         deleteLink(path, "/bonds/strength");
       },
       {"missing dataset /bonds/strength"}},
      {"missing step dataset",
       [](const std::string& path, const SampleData&) {
         deleteLink(path, "/steps/000002/positions");
       },
       {"missing dataset /steps/000002/positions"}},
      {"wrong dtype",
       [m](const std::string& path, const SampleData& s) {
         replaceDataset(path, "/bonds/pairs", ElementType::kFloat64, {m(s), 2});
       },
       {"dataset /bonds/pairs has dtype float64, expected int32"}},
      {"wrong shape",
       [m](const std::string& path, const SampleData& s) {
         replaceDataset(path, "/bonds/pairs", ElementType::kInt32, {m(s), 3});
       },
       {fmt::format("dataset /bonds/pairs has shape [{},3], expected [*,2]", bonds)}},
      {"strength shape disagrees with M",
       [m](const std::string& path, const SampleData& s) {
         replaceDataset(path, "/bonds/strength", ElementType::kFloat64, {m(s) + 4});
       },
       {fmt::format("dataset /bonds/strength has shape [{}], expected [{}]", bonds + 4, bonds)}},
      {"bond index out of range",
       [n](const std::string& path, const SampleData& s) {
         setInt32Elements(path, "/bonds/pairs", {0, static_cast<std::int32_t>(n(s) + 5)}, 2 * 5);
       },
       {fmt::format("bond 5 joins particles 0 and {}: index out of range (N = {} particles)",
                    particles + 5, particles)}},
      {"negative bond index",
       [](const std::string& path, const SampleData&) {
         setInt32Elements(path, "/bonds/pairs", {-1, 3}, 2 * 6);
       },
       {"bond 6 joins particles -1 and 3", "index out of range"}},
      {"self-bond",
       [](const std::string& path, const SampleData&) {
         setInt32Elements(path, "/bonds/pairs", {7, 7}, 2 * 3);
       },
       {"bond 3 is a self-bond of particle 7"}},
      {"duplicate bond",
       [](const std::string& path, const SampleData& s) {
         const dem::Bond first = s.lattice.bonds[1];  // bond 4 becomes bond 1, reversed
         setInt32Elements(path, "/bonds/pairs", {first.second, first.first}, 2 * 4);
       },
       {"bond 4 duplicates bond 1"}},
      {"NaN position",
       [](const std::string& path, const SampleData&) {
         setElement(path, "/steps/000002/positions", 3 * 10 + 1, std::nan(""));
       },
       {"step 2: position of particle 10 is not finite"}},
      {"infinite position",
       [](const std::string& path, const SampleData&) {
         setElement(path, "/steps/000000/positions", 3 * 4 + 2,
                    std::numeric_limits<double>::infinity());
       },
       {"step 0: position of particle 4 is not finite"}},
      {"step positions disagree with N",
       [n](const std::string& path, const SampleData& s) {
         replaceDataset(path, "/steps/000002/positions", ElementType::kFloat64, {n(s) - 1, 3});
       },
       {fmt::format("dataset /steps/000002/positions has shape [{},3], expected [{},3]",
                    particles - 1, particles)}},
      {"step bond_state disagrees with M",
       [m](const std::string& path, const SampleData& s) {
         replaceDataset(path, "/steps/000000/bond_state", ElementType::kUInt8, {m(s) + 1});
       },
       {fmt::format("dataset /steps/000000/bond_state has shape [{}], expected [{}]", bonds + 1,
                    bonds)}},
      {"truncated file",
       [](const std::string& path, const SampleData&) { truncateFile(path, 0.6); },
       {"truncated or corrupt"}},
  };
}

}  // namespace crackvis::testing
