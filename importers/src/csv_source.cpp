// The plain folder format for in-house codes (docs/data-format.md,
// "Importing a folder of CSV or NumPy files"): one bond list `bonds.csv`,
// one particle file per step `particles_<step>.csv` (or `.npy`), and an
// optional `steps.csv` of per-step time and scalars.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "scalar_table.hpp"
#include "text_input.hpp"
#include <crackvis/importers/step_source.hpp>

namespace crackvis::importers {
namespace {

// A bond of bonds.csv: the step it breaks at (source step numbers), or none.
struct ListedBond {
  SourceBond bond;
  std::optional<std::int64_t> breakStep;
  bool notch = false;
  double strength = 0.0;
};

int findColumn(const std::vector<std::string_view>& header, std::string_view name) {
  const auto found = std::find(header.begin(), header.end(), name);
  return found == header.end() ? -1 : static_cast<int>(found - header.begin());
}

// The step number of "particles_<step>.csv" / ".npy".
std::optional<std::int64_t> particleFileStep(const std::string& name, std::string& extension) {
  constexpr std::string_view kPrefix = "particles_";
  if (name.rfind(kPrefix, 0) != 0) {
    return std::nullopt;
  }
  const std::size_t dot = name.rfind('.');
  if (dot == std::string::npos) {
    return std::nullopt;
  }
  extension = name.substr(dot);
  if (extension != ".csv" && extension != ".npy") {
    return std::nullopt;
  }
  std::int64_t step = 0;
  const std::string_view digits(name.data() + kPrefix.size(), dot - kPrefix.size());
  if (digits.empty() || !std::all_of(digits.begin(), digits.end(), ::isdigit) ||
      !parseId(digits, step)) {
    return std::nullopt;
  }
  return step;
}

class CsvSource final : public StepSource {
 public:
  CsvSource() { m_description.code = "CSV folder"; }
  const SourceDescription& description() const override { return m_description; }
  int stepCount() const override { return static_cast<int>(m_files.size()); }
  std::int64_t sourceStepNumber(int index) const override {
    return std::next(m_files.begin(), index)->first;
  }
  Result<SourceStep> readStep(int index) override;
  Status open(const std::string& folder);

 private:
  Status readBondList(const std::string& path);
  Status readCsvParticles(const std::string& path, SourceStep& out) const;
  Status readNpyParticles(const std::string& path, SourceStep& out) const;

  SourceDescription m_description;
  std::map<std::int64_t, std::string> m_files;
  std::vector<ListedBond> m_bonds;
  std::optional<ScalarTable> m_steps;
  bool m_withStrength = false;
};

Status CsvSource::open(const std::string& folder) {
  if (!isFolder(folder)) {
    return notFound(
        fmt::format("{}: no such folder (the CSV import reads a folder holding "
                    "bonds.csv and particles_<step>.csv)",
                    folder));
  }
  for (const std::string& file : listFolder(folder)) {
    std::string extension;
    if (auto step = particleFileStep(baseName(file), extension)) {
      if (!m_files.emplace(*step, file).second) {
        return failedPrecondition(fmt::format("{}: step {} has two particle files ({} and {})",
                                              folder, *step, baseName(m_files[*step]),
                                              baseName(file)));
      }
    }
  }
  if (m_files.empty()) {
    return notFound(fmt::format("{}: no particles_<step>.csv or .npy files", folder));
  }
  CRACKVIS_RETURN_IF_ERROR(readBondList(folder + "/bonds.csv"));
  m_description.files.push_back(folder + "/bonds.csv");
  const std::string steps = folder + "/steps.csv";
  std::error_code error;
  if (std::filesystem::exists(steps, error)) {
    auto table = ScalarTable::read(steps);
    if (!table) {
      return table.status();
    }
    m_steps = std::move(*table);
    m_description.files.push_back(steps);
  }
  for (const auto& [step, file] : m_files) {
    m_description.files.push_back(file);
  }
  return Status::ok();
}

Status CsvSource::readBondList(const std::string& path) {
  auto input = TextInput::open(path);
  if (!input) {
    return input.status();
  }
  auto headerLine = input->expect("the header id1,id2[,break_step][,notch][,strength]");
  if (!headerLine) {
    return headerLine.status();
  }
  const auto header = splitFields(*headerLine);
  const int id1 = findColumn(header, "id1");
  const int id2 = findColumn(header, "id2");
  const int breakStep = findColumn(header, "break_step");
  const int notch = findColumn(header, "notch");
  const int strength = findColumn(header, "strength");
  if (id1 < 0 || id2 < 0) {
    return input->error(fmt::format("header '{}' lacks id1 or id2", *headerLine));
  }
  m_withStrength = strength >= 0;
  std::string line;
  while (input->next(line)) {
    const auto fields = splitFields(line);
    if (fields.empty() || fields[0].front() == '#') {
      continue;
    }
    if (fields.size() != header.size()) {
      return input->error(fmt::format("{} values for {} columns", fields.size(), header.size()));
    }
    ListedBond listed;
    if (!parseId(fields[static_cast<std::size_t>(id1)], listed.bond.first) ||
        !parseId(fields[static_cast<std::size_t>(id2)], listed.bond.second)) {
      return input->error("id1 and id2 must be integers");
    }
    if (breakStep >= 0) {
      std::int64_t step = 0;
      if (!parseId(fields[static_cast<std::size_t>(breakStep)], step)) {
        return input->error("break_step must be an integer (-1: never)");
      }
      if (step >= 0) {
        listed.breakStep = step;
      }
    }
    if (notch >= 0) {
      std::int64_t flag = 0;
      if (!parseId(fields[static_cast<std::size_t>(notch)], flag) || (flag != 0 && flag != 1)) {
        return input->error("notch must be 0 or 1");
      }
      listed.notch = flag == 1;
    }
    if (strength >= 0 &&
        !parseNumber(fields[static_cast<std::size_t>(strength)], listed.strength)) {
      return input->error("strength must be a number");
    }
    m_bonds.push_back(listed);
  }
  return Status::ok();
}

Status CsvSource::readCsvParticles(const std::string& path, SourceStep& out) const {
  auto input = TextInput::open(path);
  if (!input) {
    return input.status();
  }
  auto headerLine = input->expect("the header id,x,y,z,radius[,group][,vx,vy,vz][,...]");
  if (!headerLine) {
    return headerLine.status();
  }
  const auto header = splitFields(*headerLine);
  const int id = findColumn(header, "id");
  const int x = findColumn(header, "x");
  const int y = findColumn(header, "y");
  const int z = findColumn(header, "z");
  const int radius = findColumn(header, "radius");
  const int group = findColumn(header, "group");
  const int vx = findColumn(header, "vx");
  const int vy = findColumn(header, "vy");
  const int vz = findColumn(header, "vz");
  if (id < 0 || x < 0 || y < 0 || z < 0 || radius < 0) {
    return input->error(fmt::format("header '{}' lacks one of id, x, y, z, radius", *headerLine));
  }
  const bool velocities = vx >= 0 && vy >= 0 && vz >= 0;
  std::vector<std::size_t> extraColumns;
  for (std::size_t c = 0; c < header.size(); ++c) {
    const int column = static_cast<int>(c);
    if (column != id && column != x && column != y && column != z && column != radius &&
        column != group && (!velocities || (column != vx && column != vy && column != vz))) {
      extraColumns.push_back(c);
      out.extras.push_back({safeName(header[c]), dem::ExtraOwner::kParticles, 1, {}});
    }
  }
  std::string line;
  while (input->next(line)) {
    const auto fields = splitFields(line);
    if (fields.empty()) {
      continue;
    }
    if (fields.size() != header.size()) {
      return input->error(fmt::format("{} values for {} columns", fields.size(), header.size()));
    }
    auto number = [&](int column, double& value) -> Status {
      if (!parseNumber(fields[static_cast<std::size_t>(column)], value)) {
        return input->error(fmt::format("{} '{}' is not a number",
                                        header[static_cast<std::size_t>(column)],
                                        fields[static_cast<std::size_t>(column)]));
      }
      return Status::ok();
    };
    std::int64_t particle = 0;
    if (!parseId(fields[static_cast<std::size_t>(id)], particle)) {
      return input->error(
          fmt::format("id '{}' is not an integer", fields[static_cast<std::size_t>(id)]));
    }
    dem::Vec3 p;
    double r = 0.0;
    CRACKVIS_RETURN_IF_ERROR(number(x, p.x));
    CRACKVIS_RETURN_IF_ERROR(number(y, p.y));
    CRACKVIS_RETURN_IF_ERROR(number(z, p.z));
    CRACKVIS_RETURN_IF_ERROR(number(radius, r));
    out.ids.push_back(particle);
    out.positions.push_back(p);
    out.radius.push_back(r);
    if (group >= 0) {
      std::int64_t label = 0;
      if (!parseId(fields[static_cast<std::size_t>(group)], label)) {
        return input->error("group must be an integer");
      }
      out.group.push_back(static_cast<std::int32_t>(label));
    }
    if (velocities) {
      double v[3];
      CRACKVIS_RETURN_IF_ERROR(number(vx, v[0]));
      CRACKVIS_RETURN_IF_ERROR(number(vy, v[1]));
      CRACKVIS_RETURN_IF_ERROR(number(vz, v[2]));
      out.velocities.push_back(
          {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])});
    }
    for (std::size_t e = 0; e < extraColumns.size(); ++e) {
      double value = 0.0;
      CRACKVIS_RETURN_IF_ERROR(number(static_cast<int>(extraColumns[e]), value));
      out.extras[e].values.push_back(value);
    }
  }
  return Status::ok();
}

// NumPy .npy version 1/2: a little-endian float64 (or float32) C-order
// array of shape (n, 5) or (n, 6): id, x, y, z, radius[, group].
Status CsvSource::readNpyParticles(const std::string& path, SourceStep& out) const {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  if (!in || std::memcmp(magic, "\x93NUMPY", 6) != 0) {
    return failedPrecondition(fmt::format("{}: not a NumPy .npy file", path));
  }
  std::uint32_t headerBytes = 0;
  if (magic[6] == 1) {
    unsigned char size[2];
    in.read(reinterpret_cast<char*>(size), 2);
    headerBytes = size[0] | (size[1] << 8);
  } else {
    unsigned char size[4];
    in.read(reinterpret_cast<char*>(size), 4);
    headerBytes = size[0] | (size[1] << 8) | (size[2] << 16) | (std::uint32_t{size[3]} << 24);
  }
  if (!in || headerBytes > 65536) {
    return failedPrecondition(fmt::format("{}: truncated .npy header", path));
  }
  std::string header(headerBytes, '\0');
  in.read(header.data(), headerBytes);
  const bool f8 = header.find("'descr': '<f8'") != std::string::npos;
  const bool f4 = header.find("'descr': '<f4'") != std::string::npos;
  if (!in || (!f8 && !f4) || header.find("'fortran_order': False") == std::string::npos) {
    return failedPrecondition(
        fmt::format("{}: expected a C-order little-endian float64 or float32 array (header {})",
                    path, header.substr(0, header.find('}') + 1)));
  }
  const std::size_t shapeAt = header.find("'shape': (");
  unsigned long rows = 0;
  unsigned long columns = 0;
  if (shapeAt == std::string::npos ||
      std::sscanf(header.c_str() + shapeAt, "'shape': (%lu, %lu)", &rows, &columns) != 2 ||
      (columns != 5 && columns != 6)) {
    return failedPrecondition(
        fmt::format("{}: expected shape (n, 5) or (n, 6): id, x, y, z, radius[, group]", path));
  }
  const std::size_t bytes = f8 ? 8 : 4;
  // The header's shape is believed only as far as the file's length backs
  // it: a 215-byte file declaring 400 million rows must not allocate 16 GB.
  std::error_code error;
  const std::uintmax_t fileBytes = std::filesystem::file_size(path, error);
  const std::uintmax_t dataStart = static_cast<std::uintmax_t>(in.tellg());
  const std::uintmax_t stored = !error && fileBytes > dataStart ? fileBytes - dataStart : 0;
  if (rows > stored / (columns * bytes)) {
    return failedPrecondition(fmt::format(
        "{}: truncated: the header declares {} x {} values ({} bytes), the file holds {} bytes "
        "of data",
        path, rows, columns, static_cast<double>(rows) * static_cast<double>(columns * bytes),
        stored));
  }
  std::vector<char> data(rows * columns * bytes);
  in.read(data.data(), static_cast<std::streamsize>(data.size()));
  if (!in) {
    return Status(
        StatusCode::kFailedPrecondition,
        fmt::format("{}: truncated: the header promises {} x {} values", path, rows, columns));
  }
  auto value = [&](std::size_t row, std::size_t column) {
    const char* at = data.data() + (row * columns + column) * bytes;
    if (f8) {
      double v;
      std::memcpy(&v, at, 8);
      return v;
    }
    float v;
    std::memcpy(&v, at, 4);
    return static_cast<double>(v);
  };
  for (std::size_t row = 0; row < rows; ++row) {
    const double id = value(row, 0);
    if (!std::isfinite(id) || id != std::floor(id) || std::abs(id) > 9e15) {
      return failedPrecondition(fmt::format("{}: row {}: id {} is not an integer", path, row, id));
    }
    out.ids.push_back(static_cast<std::int64_t>(id));
    out.positions.push_back({value(row, 1), value(row, 2), value(row, 3)});
    out.radius.push_back(value(row, 4));
    if (columns == 6) {
      out.group.push_back(static_cast<std::int32_t>(value(row, 5)));
    }
  }
  return Status::ok();
}

Result<SourceStep> CsvSource::readStep(int index) {
  const auto& [step, file] = *std::next(m_files.begin(), index);
  SourceStep out;
  out.sourceStep = step;
  out.origin = file;
  const bool npy = file.size() > 4 && file.compare(file.size() - 4, 4, ".npy") == 0;
  CRACKVIS_RETURN_IF_ERROR(npy ? readNpyParticles(file, out) : readCsvParticles(file, out));
  for (const ListedBond& listed : m_bonds) {
    SourceBond bond = listed.bond;
    bond.cohesive = !listed.notch && (!listed.breakStep || step < *listed.breakStep);
    out.bonds.push_back(bond);
    if (m_withStrength) {
      out.bondStrength.push_back(listed.strength);
    }
  }
  if (m_steps) {
    for (const dem::StepScalar& scalar : m_steps->at(step)) {
      if (scalar.name == "time") {
        out.time = scalar.value;
        out.timeKnown = true;
      } else {
        out.scalars.push_back(scalar);
      }
    }
  }
  return out;
}

}  // namespace

Result<std::unique_ptr<StepSource>> openCsv(const std::vector<std::string>& inputs) {
  if (inputs.size() != 1) {
    return invalidArgument("the CSV import reads one folder (bonds.csv, particles_<step>.csv)");
  }
  auto source = std::make_unique<CsvSource>();
  CRACKVIS_RETURN_IF_ERROR(source->open(inputs.front()));
  return std::unique_ptr<StepSource>(std::move(source));
}

}  // namespace crackvis::importers
