// Per-step scalars from a table a DEM script wrote beside its dumps: LAMMPS
// `fix print` files, Yade's plot.saveDataTxt, a CSV. One header line of
// names (a leading '#' is allowed), then one row per record; the column
// named step, timestep, iter or iteration says which source step a row
// belongs to, the other columns become step scalars of that name.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::importers {

class ScalarTable {
 public:
  static Result<ScalarTable> read(const std::string& path);
  // The scalars of the row for `sourceStep` (the last one, if a step was
  // recorded twice); none when the table has no such row.
  std::vector<dem::StepScalar> at(std::int64_t sourceStep) const;
  const std::vector<std::string>& names() const { return m_names; }

 private:
  std::vector<std::string> m_names;  // without the step column
  std::map<std::int64_t, std::vector<double>> m_rows;
};

}  // namespace crackvis::importers
