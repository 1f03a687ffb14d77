// A crackvis-dem file opened for crack extraction: the lattice and its bond
// graph read once, then one step at a time as a StepInput for the methods.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <crackvis/cracks/extractor.hpp>
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::cracks {

class DemSeries {
 public:
  static Result<std::unique_ptr<DemSeries>> open(const std::string& path);

  const dem::DemFileInfo& info() const { return m_reader.info(); }
  const dem::Lattice& lattice() const { return m_lattice; }
  const BondGraph& graph() const { return *m_graph; }
  int stepCount() const { return m_reader.stepCount(); }

  // Reads step k (and once step 0, the reference configuration); the
  // returned input views this object's buffers and stays valid until the
  // next load.
  Result<StepInput> load(int step);
  const dem::StepState& state() const { return m_state; }

 private:
  explicit DemSeries(dem::DemFileReader reader) : m_reader(std::move(reader)) {}

  dem::DemFileReader m_reader;
  dem::Lattice m_lattice;
  std::vector<std::int32_t> m_breakSteps;
  std::unique_ptr<BondGraph> m_graph;
  dem::StepState m_state;
  std::vector<dem::Vec3> m_reference;
};

}  // namespace crackvis::cracks
