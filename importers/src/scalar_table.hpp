// Per-step scalars from a table a DEM script wrote beside its dumps: LAMMPS
// `fix print` files, Yade's plot.saveDataTxt, a CSV. One header line of
// names (a leading '#' is allowed), then one row per record; the column
// named step, timestep, iter or iteration says which source step a row
// belongs to, the other columns become step scalars of that name.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::importers {

// A column whose first value is not a number (Yade's phase label, a
// comment column) is skipped, and named in textColumns(); a later value
// that is not a number in a numeric column is an error naming its line.
class ScalarTable {
 public:
  static Result<ScalarTable> read(const std::string& path);
  // The scalars of the row for `sourceStep` (the last one, if a step was
  // recorded twice); none when the table has no such row.
  std::vector<dem::StepScalar> at(std::int64_t sourceStep) const;
  bool has(std::int64_t sourceStep) const { return m_rows.count(sourceStep) != 0; }
  const std::vector<std::string>& names() const { return m_names; }
  const std::vector<std::string>& textColumns() const { return m_textColumns; }
  std::size_t rowCount() const { return m_rows.size(); }
  std::int64_t firstStep() const { return m_rows.empty() ? 0 : m_rows.begin()->first; }
  std::int64_t lastStep() const { return m_rows.empty() ? 0 : m_rows.rbegin()->first; }
  // Whether fittedTime() can answer: a time column with two rows or more.
  bool fitsTime() const { return fittedTime(0).has_value(); }
  // The time of `sourceStep` on the straight line through the table's
  // (step, time) rows (least squares): for a step the table has no row for,
  // in the table's unit. None without a time column or two rows of it.
  std::optional<double> fittedTime(std::int64_t sourceStep) const;

 private:
  std::vector<std::string> m_names;  // without the step column and text columns
  std::vector<std::string> m_textColumns;
  std::map<std::int64_t, std::vector<double>> m_rows;
};

}  // namespace crackvis::importers
