// LAMMPS: `dump custom` particle files plus `dump local` bond files, one or
// many steps per file (docs/data-format.md, "Importing"). Bonds that
// fix bond/break deletes, or that bond_style quartic sets to type 0, are
// simply not listed any more; bonds turned off by delete_bonds are listed
// with a negative type, which reads as "not cohesive".
#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "text_input.hpp"
#include <crackvis/importers/step_source.hpp>

namespace crackvis::importers {
namespace {

enum class DumpKind { kAtoms, kLocal };

// Where one step's block starts in a dump file.
struct Block {
  std::string file;
  std::streamoff offset = 0;
  int line = 0;
};

struct Columns {
  int id = -1, type = -1, x = -1, y = -1, z = -1, radius = -1, diameter = -1;
  int vx = -1, vy = -1, vz = -1;
  bool scaled = false;
  std::vector<std::pair<int, std::string>> extras;  // column, name
};

Result<Columns> atomColumns(const TextInput& input, std::string_view header) {
  Columns c;
  const auto names = splitTokens(header);
  for (std::size_t i = 2; i < names.size(); ++i) {  // after "ITEM: ATOMS"
    const int column = static_cast<int>(i - 2);
    const std::string_view name = names[i];
    if (name == "id") {
      c.id = column;
    } else if (name == "type") {
      c.type = column;
    } else if (name == "x" || name == "xu") {
      c.x = column;
    } else if (name == "y" || name == "yu") {
      c.y = column;
    } else if (name == "z" || name == "zu") {
      c.z = column;
    } else if (name == "xs" || name == "ys" || name == "zs") {
      c.scaled = true;
      (name == "xs" ? c.x : name == "ys" ? c.y : c.z) = column;
    } else if (name == "radius") {
      c.radius = column;
    } else if (name == "diameter") {
      c.diameter = column;
    } else if (name == "vx") {
      c.vx = column;
    } else if (name == "vy") {
      c.vy = column;
    } else if (name == "vz") {
      c.vz = column;
    } else {
      c.extras.emplace_back(column, safeName(name));
    }
  }
  if (c.id < 0 || c.x < 0 || c.y < 0 || c.z < 0) {
    return input.error(fmt::format(
        "the dump's columns '{}' lack id, x, y or z (dump custom ... id type x y z radius)",
        header));
  }
  if (c.radius < 0 && c.diameter < 0) {
    return input.error(fmt::format(
        "the dump's columns '{}' have no radius or diameter (atom_style sphere writes them)",
        header));
  }
  return c;
}

class LammpsSource final : public StepSource {
 public:
  LammpsSource() { m_description.code = "LAMMPS"; }
  const SourceDescription& description() const override { return m_description; }
  int stepCount() const override { return static_cast<int>(m_steps.size()); }
  std::int64_t sourceStepNumber(int index) const override {
    return m_steps[static_cast<std::size_t>(index)];
  }
  Result<SourceStep> readStep(int index) override;

  Status add(const std::string& file);
  Status finish();

 private:
  Status index(TextInput& input, DumpKind kind);
  Status readLog(TextInput& input, const std::string& first);
  Status readAtoms(const Block& block, std::int64_t step, SourceStep& out) const;
  Status readBonds(const Block& block, std::int64_t step, SourceStep& out) const;

  SourceDescription m_description;
  std::map<std::int64_t, Block> m_atoms;
  std::map<std::int64_t, Block> m_bonds;
  std::vector<std::int64_t> m_steps;
  double m_timestep = 0.0;  // s per step, from the log; 0 unknown
};

// Reads "ITEM: TIMESTEP" and the items before the rows of one block;
// leaves `input` at the first row. Returns the column header line.
struct BlockHeader {
  std::int64_t step = 0;
  bool timeKnown = false;
  double time = 0.0;
  std::int64_t rows = 0;
  DumpKind kind = DumpKind::kAtoms;
  std::string columns;
  std::array<std::array<double, 2>, 3> box{};
};

Result<BlockHeader> readBlockHeader(TextInput& input, std::string first) {
  BlockHeader header;
  std::string line = std::move(first);
  while (true) {
    if (line.rfind("ITEM: TIMESTEP", 0) == 0) {
      auto value = input.expect("the step number after ITEM: TIMESTEP");
      if (!value || !parseId(*value, header.step)) {
        return value ? input.error(fmt::format("step number '{}' is not an integer", *value))
                     : value.status();
      }
    } else if (line.rfind("ITEM: TIME", 0) == 0) {
      auto value = input.expect("the time after ITEM: TIME");
      if (!value || !parseNumber(*value, header.time)) {
        return value ? input.error(fmt::format("time '{}' is not a number", *value))
                     : value.status();
      }
      header.timeKnown = true;
    } else if (line.rfind("ITEM: UNITS", 0) == 0) {
      if (auto skipped = input.expect("the units after ITEM: UNITS"); !skipped) {
        return skipped.status();
      }
    } else if (line.rfind("ITEM: NUMBER OF ", 0) == 0) {
      header.kind = line == "ITEM: NUMBER OF ATOMS" ? DumpKind::kAtoms : DumpKind::kLocal;
      auto value = input.expect("a row count");
      if (!value || !parseId(*value, header.rows) || header.rows < 0) {
        return value ? input.error(fmt::format("row count '{}' is not a count", *value))
                     : value.status();
      }
      // A count is believed only as far as the file could hold its rows
      // (two bytes each at least): readers allocate by it.
      if (const std::uint64_t left = input.bytesLeft();
          static_cast<std::uint64_t>(header.rows) > left / 2) {
        return input.error(fmt::format(
            "the header declares {} rows, but only {} bytes follow (truncated or corrupt?)",
            header.rows, left));
      }
    } else if (line.rfind("ITEM: BOX BOUNDS", 0) == 0) {
      for (auto& axis : header.box) {
        auto bounds = input.expect("a box bounds line");
        if (!bounds) {
          return bounds.status();
        }
        const auto tokens = splitTokens(*bounds);
        if (tokens.size() < 2 || !parseNumber(tokens[0], axis[0]) ||
            !parseNumber(tokens[1], axis[1])) {
          return input.error(fmt::format("box bounds '{}' are not two numbers", *bounds));
        }
      }
    } else if (line.rfind("ITEM: ", 0) == 0) {
      header.columns = line;  // ITEM: ATOMS ... or ITEM: ENTRIES ...
      return header;
    } else {
      return input.error(fmt::format("expected an ITEM: line, found '{}'", line.substr(0, 80)));
    }
    auto next = input.expect("the next ITEM: line");
    if (!next) {
      return next.status();
    }
    line = std::move(*next);
  }
}

// A block's reader, positioned at its first row.
struct OpenedBlock {
  TextInput input;
  BlockHeader header;
};

Result<OpenedBlock> openBlock(const Block& block) {
  auto input = TextInput::open(block.file);
  if (!input) {
    return input.status();
  }
  input->seek(block.offset, block.line);
  std::string line;
  while (input->next(line) && line.empty()) {
  }
  auto header = readBlockHeader(*input, line);
  if (!header) {
    return header.status();
  }
  return OpenedBlock{std::move(*input), std::move(*header)};
}

Status LammpsSource::index(TextInput& input, DumpKind kind) {
  auto& blocks = kind == DumpKind::kAtoms ? m_atoms : m_bonds;
  std::string line;
  while (true) {
    const std::streamoff offset = input.offset();
    const int lineNumber = input.lineNumber();
    if (!input.next(line)) {
      return Status::ok();
    }
    if (line.empty()) {
      continue;
    }
    auto header = readBlockHeader(input, line);
    if (!header) {
      return header.status();
    }
    if (header->kind != kind) {
      return input.error("a dump file mixes particle (ATOMS) and bond (ENTRIES) blocks");
    }
    if (!blocks.emplace(header->step, Block{input.path(), offset, lineNumber}).second) {
      return input.error(fmt::format("step {} appears twice among the {} dumps", header->step,
                                     kind == DumpKind::kAtoms ? "particle" : "bond"));
    }
    for (std::int64_t row = 0; row < header->rows; ++row) {
      if (!input.next(line)) {
        return Status(
            StatusCode::kFailedPrecondition,
            fmt::format("{}:{}: truncated: step {} promises {} rows, the file ends "
                        "after {}",
                        input.path(), input.lineNumber(), header->step, header->rows, row));
      }
    }
  }
}

Status LammpsSource::add(const std::string& file) {
  auto input = TextInput::open(file);
  if (!input) {
    return input.status();
  }
  std::string first;
  while (input->next(first) && first.empty()) {
  }
  if (baseName(file).rfind("log.", 0) == 0 || first.rfind("LAMMPS (", 0) == 0) {
    return readLog(*input, first);
  }
  if (first.rfind("ITEM: ", 0) != 0) {
    return input->error("not a LAMMPS dump (expected ITEM: TIMESTEP on the first line)");
  }
  auto header = readBlockHeader(*input, first);
  if (!header) {
    return header.status();
  }
  input->seek(0, 0);
  m_description.files.push_back(file);
  return index(*input, header->kind);
}

// The log names the version ("LAMMPS (29 Sep 2021 - Update 2)") and echoes
// the input, whose last `timestep` command gives the step size: dumps
// written without `dump_modify time yes` then still get times.
Status LammpsSource::readLog(TextInput& input, const std::string& first) {
  if (first.rfind("LAMMPS (", 0) == 0 && first.back() == ')') {
    m_description.version = first.substr(8, first.size() - 9);
  }
  std::string line;
  while (input.next(line)) {
    const auto tokens = splitTokens(line);
    double dt = 0.0;
    if (tokens.size() == 2 && tokens[0] == "timestep" && parseNumber(tokens[1], dt) && dt > 0.0) {
      m_timestep = dt;
    }
  }
  m_description.files.push_back(input.path());
  return Status::ok();
}

Status LammpsSource::finish() {
  if (m_atoms.empty()) {
    return notFound(
        "no LAMMPS particle dump among the inputs (dump custom ... id type x y z radius)");
  }
  if (m_bonds.empty()) {
    return notFound(
        "no LAMMPS bond dump among the inputs (compute property/local batom1 batom2 btype + "
        "dump local)");
  }
  for (const auto& [step, block] : m_atoms) {
    if (!m_bonds.contains(step)) {
      return failedPrecondition(
          fmt::format("step {} ({}) has a particle dump but no bond dump", step, block.file));
    }
    m_steps.push_back(step);
  }
  for (const auto& [step, block] : m_bonds) {
    if (!m_atoms.contains(step)) {
      return failedPrecondition(
          fmt::format("step {} ({}) has a bond dump but no particle dump", step, block.file));
    }
  }
  return Status::ok();
}

Status LammpsSource::readAtoms(const Block& block, std::int64_t step, SourceStep& out) const {
  auto opened = openBlock(block);
  if (!opened) {
    return opened.status();
  }
  TextInput& input = opened->input;
  const BlockHeader& header = opened->header;
  std::string line;
  auto columns = atomColumns(input, header.columns);
  if (!columns) {
    return columns.status();
  }
  out.timeKnown = header.timeKnown;
  out.time = header.time;
  const auto n = static_cast<std::size_t>(header.rows);
  out.ids.resize(n);
  out.positions.resize(n);
  out.radius.resize(n);
  if (columns->type >= 0) {
    out.group.resize(n);
  }
  const bool velocities = columns->vx >= 0 && columns->vy >= 0 && columns->vz >= 0;
  if (velocities) {
    out.velocities.resize(n);
  }
  for (const auto& [column, name] : columns->extras) {
    out.extras.push_back({name, dem::ExtraOwner::kParticles, 1, std::vector<double>(n)});
  }
  const std::size_t width = splitTokens(header.columns).size() - 2;
  for (std::size_t row = 0; row < n; ++row) {
    if (!input.next(line)) {
      return Status(
          StatusCode::kFailedPrecondition,
          fmt::format("{}:{}: truncated in step {}", block.file, input.lineNumber(), step));
    }
    const auto tokens = splitTokens(line);
    if (tokens.size() != width) {
      return input.error(
          fmt::format("{} values, the header names {} columns", tokens.size(), width));
    }
    auto number = [&](int column, double& value) -> Status {
      if (!parseNumber(tokens[static_cast<std::size_t>(column)], value)) {
        return input.error(fmt::format("column {}: '{}' is not a number", column + 1,
                                       tokens[static_cast<std::size_t>(column)]));
      }
      return Status::ok();
    };
    if (!parseId(tokens[static_cast<std::size_t>(columns->id)], out.ids[row])) {
      return input.error(
          fmt::format("id '{}' is not an integer", tokens[static_cast<std::size_t>(columns->id)]));
    }
    dem::Vec3& p = out.positions[row];
    CRACKVIS_RETURN_IF_ERROR(number(columns->x, p.x));
    CRACKVIS_RETURN_IF_ERROR(number(columns->y, p.y));
    CRACKVIS_RETURN_IF_ERROR(number(columns->z, p.z));
    if (columns->scaled) {
      p = {header.box[0][0] + p.x * (header.box[0][1] - header.box[0][0]),
           header.box[1][0] + p.y * (header.box[1][1] - header.box[1][0]),
           header.box[2][0] + p.z * (header.box[2][1] - header.box[2][0])};
    }
    double size = 0.0;
    CRACKVIS_RETURN_IF_ERROR(
        number(columns->radius >= 0 ? columns->radius : columns->diameter, size));
    out.radius[row] = columns->radius >= 0 ? size : 0.5 * size;
    if (columns->type >= 0) {
      std::int64_t type = 0;
      if (!parseId(tokens[static_cast<std::size_t>(columns->type)], type)) {
        return input.error("type is not an integer");
      }
      out.group[row] = static_cast<std::int32_t>(type);
    }
    if (velocities) {
      double v[3];
      CRACKVIS_RETURN_IF_ERROR(number(columns->vx, v[0]));
      CRACKVIS_RETURN_IF_ERROR(number(columns->vy, v[1]));
      CRACKVIS_RETURN_IF_ERROR(number(columns->vz, v[2]));
      out.velocities[row] = {static_cast<float>(v[0]), static_cast<float>(v[1]),
                             static_cast<float>(v[2])};
    }
    for (std::size_t e = 0; e < columns->extras.size(); ++e) {
      CRACKVIS_RETURN_IF_ERROR(number(columns->extras[e].first, out.extras[e].values[row]));
    }
  }
  return Status::ok();
}

Status LammpsSource::readBonds(const Block& block, std::int64_t step, SourceStep& out) const {
  auto opened = openBlock(block);
  if (!opened) {
    return opened.status();
  }
  TextInput& input = opened->input;
  const BlockHeader& header = opened->header;
  std::string line;
  // Columns: [index] atom1 atom2 [type] [more...]: the first two after an
  // optional `index` are the atom ids (compute property/local batom1
  // batom2 btype), the next the bond type, any further ones per-bond extras.
  const auto names = splitTokens(header.columns);
  std::size_t firstId = 2;
  if (names.size() > 2 && names[2] == "index") {
    ++firstId;
  }
  if (names.size() < firstId + 2) {
    return input.error(fmt::format(
        "the bond dump's columns '{}' need two atom ids (compute property/local batom1 batom2 "
        "btype)",
        header.columns));
  }
  const bool typed = names.size() > firstId + 2;
  std::vector<std::size_t> extraColumns;
  for (std::size_t i = firstId + 3; i < names.size(); ++i) {
    extraColumns.push_back(i - 2);
    out.extras.push_back({safeName(names[i]), dem::ExtraOwner::kBonds, 1, {}});
  }
  const std::size_t width = names.size() - 2;
  const std::size_t idColumn = firstId - 2;
  out.bonds.reserve(static_cast<std::size_t>(header.rows));
  for (std::int64_t row = 0; row < header.rows; ++row) {
    if (!input.next(line)) {
      return Status(
          StatusCode::kFailedPrecondition,
          fmt::format("{}:{}: truncated in step {}", block.file, input.lineNumber(), step));
    }
    const auto tokens = splitTokens(line);
    if (tokens.size() != width) {
      return input.error(
          fmt::format("{} values, the header names {} columns", tokens.size(), width));
    }
    SourceBond bond;
    if (!parseId(tokens[idColumn], bond.first) || !parseId(tokens[idColumn + 1], bond.second)) {
      return input.error(fmt::format(
          "atom ids '{}' '{}' are not integers (print them exactly: dump_modify ... format "
          "float %.15g)",
          tokens[idColumn], tokens[idColumn + 1]));
    }
    if (typed) {
      double type = 0.0;
      if (!parseNumber(tokens[idColumn + 2], type)) {
        return input.error(fmt::format("bond type '{}' is not a number", tokens[idColumn + 2]));
      }
      bond.cohesive = type > 0.0;
    }
    out.bonds.push_back(bond);
    for (std::size_t e = 0; e < extraColumns.size(); ++e) {
      double value = 0.0;
      if (!parseNumber(tokens[extraColumns[e]], value)) {
        return input.error(fmt::format("column {}: '{}' is not a number", extraColumns[e] + 1,
                                       tokens[extraColumns[e]]));
      }
      out.extras[e].values.push_back(value);
    }
  }
  return Status::ok();
}

Result<SourceStep> LammpsSource::readStep(int index) {
  const std::int64_t step = m_steps[static_cast<std::size_t>(index)];
  const Block& atoms = m_atoms.at(step);
  const Block& bonds = m_bonds.at(step);
  SourceStep out;
  out.sourceStep = step;
  out.origin = atoms.file == bonds.file
                   ? atoms.file
                   : fmt::format("{} + {}", baseName(atoms.file), baseName(bonds.file));
  CRACKVIS_RETURN_IF_ERROR(readAtoms(atoms, step, out));
  CRACKVIS_RETURN_IF_ERROR(readBonds(bonds, step, out));
  if (!out.timeKnown && m_timestep > 0.0) {
    out.time = static_cast<double>(step) * m_timestep;
    out.timeKnown = true;
  }
  return out;
}

}  // namespace

Result<std::unique_ptr<StepSource>> openLammps(const std::vector<std::string>& inputs) {
  auto source = std::make_unique<LammpsSource>();
  // In a folder: the dumps and the log, known by their first line.
  auto wanted = [](const std::string& file) {
    auto probe = TextInput::open(file);
    std::string first;
    return probe && probe->next(first) &&
           (first.rfind("ITEM: ", 0) == 0 || first.rfind("LAMMPS (", 0) == 0);
  };
  CRACKVIS_RETURN_IF_ERROR(
      addInputs(inputs, wanted, [&](const std::string& file) { return source->add(file); }));
  CRACKVIS_RETURN_IF_ERROR(source->finish());
  return std::unique_ptr<StepSource>(std::move(source));
}

}  // namespace crackvis::importers
