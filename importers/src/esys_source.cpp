// ESyS-Particle: the snapshot series CheckPointPrms writes. Per saved step a
// master file `<prefix>_t=<step>_0.txt` names one file per worker process;
// each worker file lists its particles (id in column 5, tag in column 6),
// then its bonded interaction groups as `id1 id2 tag` lines. A bond that
// broke is simply no longer listed.
#include <algorithm>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "text_input.hpp"
#include <crackvis/importers/step_source.hpp>

namespace crackvis::importers {
namespace {

// The step and prefix of "<prefix>_t=<step>_<rank>.txt".
struct SnapshotName {
  std::string prefix;
  std::int64_t step = 0;
  int rank = 0;
};

std::optional<SnapshotName> parseSnapshotName(const std::string& path) {
  const std::string name = baseName(path);
  const std::size_t t = name.rfind("_t=");
  const std::size_t rankAt = name.rfind('_');
  if (t == std::string::npos || rankAt == std::string::npos || rankAt <= t + 3 || name.size() < 4 ||
      name.compare(name.size() - 4, 4, ".txt") != 0) {
    return std::nullopt;
  }
  SnapshotName parsed;
  parsed.prefix = path.substr(0, path.size() - name.size() + t);
  std::int64_t rank = 0;
  if (!parseId(std::string_view(name).substr(t + 3, rankAt - t - 3), parsed.step) ||
      !parseId(std::string_view(name).substr(rankAt + 1, name.size() - 4 - rankAt - 1), rank)) {
    return std::nullopt;
  }
  parsed.rank = static_cast<int>(rank);
  return parsed;
}

// Particle line of a snapshot: pos(0-2) rad(3) id(4) tag(5) mass(6)
// initPos(7-9) oldPos(10-12) vel(13-15) force(16-18) circShift(19-21), then
// for rotational spheres quat(22-25) angVel(26-28).
constexpr std::size_t kParticleTokens = 22;
constexpr std::size_t kRotParticleTokens = 29;

// The master file: "V 3", the number of steps, the step size, this step,
// a version line, BoundingBox, PeriodicBoundaries, Dimension, then the
// worker files.
struct Master {
  double stepSize = 0.0;
  std::int64_t step = 0;
  std::string version;
  int dimension = 3;
  std::vector<std::string> workers;
};

Result<Master> readMaster(const std::string& path) {
  auto input = TextInput::open(path);
  if (!input) {
    return input.status();
  }
  Master master;
  auto format = input->expect("the format line V <n>");
  if (!format) {
    return format.status();
  }
  if (format->rfind("V ", 0) != 0) {
    return input->error(fmt::format(
        "'{}': not an ESyS-Particle snapshot master file (expected V 3 on the first line)",
        format->substr(0, 40)));
  }
  std::string line;
  std::vector<std::string> lines;
  while (input->next(line)) {
    lines.push_back(line);
  }
  // Lines after V: steps, step size, step, version; then keyword lines.
  if (lines.size() < 4 || !parseNumber(lines[1], master.stepSize) ||
      !parseId(lines[2], master.step)) {
    return Status(StatusCode::kFailedPrecondition,
                  fmt::format("{}: truncated or malformed header (expected the step count, step "
                              "size and step after '{}')",
                              path, *format));
  }
  master.version = lines[3];
  while (!master.version.empty() && master.version.back() == ' ') {
    master.version.pop_back();
  }
  bool afterDimension = false;
  for (std::size_t i = 4; i < lines.size(); ++i) {
    const auto tokens = splitTokens(lines[i]);
    if (tokens.empty()) {
      continue;
    }
    if (tokens[0] == "Dimension") {
      master.dimension = tokens.size() > 1 && tokens[1] == "2D" ? 2 : 3;
      afterDimension = true;
    } else if (afterDimension) {
      for (std::string_view file : tokens) {
        master.workers.emplace_back(file);
      }
    }
  }
  if (master.workers.empty()) {
    return Status(StatusCode::kFailedPrecondition,
                  fmt::format("{}: names no worker files (truncated?)", path));
  }
  return master;
}

class EsysSource final : public StepSource {
 public:
  EsysSource() { m_description.code = "ESyS-Particle"; }
  const SourceDescription& description() const override { return m_description; }
  int stepCount() const override { return static_cast<int>(m_masters.size()); }
  std::int64_t sourceStepNumber(int index) const override {
    return std::next(m_masters.begin(), index)->first;
  }
  Result<SourceStep> readStep(int index) override;
  Status add(const std::string& path);
  Status finish();

 private:
  Status readWorker(const std::string& path, SourceStep& out) const;

  SourceDescription m_description;
  std::map<std::int64_t, std::string> m_masters;
};

Status EsysSource::add(const std::string& path) {
  auto name = parseSnapshotName(path);
  if (!name) {
    return invalidArgument(fmt::format(
        "{}: not an ESyS-Particle snapshot (expected <prefix>_t=<step>_<rank>.txt)", path));
  }
  if (name->rank != 0) {
    return Status::ok();  // worker files are reached through their master
  }
  if (!m_masters.emplace(name->step, path).second) {
    return failedPrecondition(fmt::format("{}: step {} appears twice", path, name->step));
  }
  m_description.files.push_back(path);
  return Status::ok();
}

Status EsysSource::finish() {
  if (m_masters.empty()) {
    return notFound(
        "no ESyS-Particle snapshot among the inputs (CheckPointPrms writes "
        "<prefix>_t=<step>_0.txt)");
  }
  // The version and dimension come from the first master file.
  auto master = readMaster(m_masters.begin()->second);
  if (!master) {
    return master.status();
  }
  m_description.version = master->version;
  m_description.dimension = master->dimension;
  return Status::ok();
}

Status EsysSource::readWorker(const std::string& path, SourceStep& out) const {
  auto input = TextInput::open(path);
  if (!input) {
    return input.status();
  }
  // Whitespace tokens, whatever the line breaks (ESyS places them loosely).
  std::string line;
  std::vector<std::string> tokens;
  std::vector<int> lineOf;
  while (input->next(line)) {
    for (std::string_view token : splitTokens(line)) {
      tokens.emplace_back(token);
      lineOf.push_back(input->lineNumber());
    }
  }
  std::size_t at = 0;
  auto fail = [&](const std::string& what) {
    const int where = at < lineOf.size() ? lineOf[at] : input->lineNumber();
    return Status(StatusCode::kFailedPrecondition,
                  fmt::format("{}:{}: {}", path, where,
                              at < tokens.size() ? what : "truncated: expected " + what));
  };
  std::int64_t count = 0;
  if (at >= tokens.size() || !parseId(tokens[at], count) || count < 0) {
    return fail("the particle count");
  }
  ++at;
  // The line width tells plain from rotational spheres.
  std::size_t width = kParticleTokens;
  if (count > 0 && at < lineOf.size()) {
    const int firstLine = lineOf[at];
    width = static_cast<std::size_t>(
        std::count(lineOf.begin() + static_cast<std::ptrdiff_t>(at), lineOf.end(), firstLine));
    if (width != kParticleTokens && width != kRotParticleTokens) {
      return fail(fmt::format("a particle line of {} values, expected {} or {}", width,
                              kParticleTokens, kRotParticleTokens));
    }
  }
  out.extras.push_back(dem::ExtraArray{"force", dem::ExtraOwner::kParticles, 3, {}});
  const std::size_t forceIndex = out.extras.size() - 1;
  for (std::int64_t p = 0; p < count; ++p) {
    if (at + width > tokens.size()) {
      at = tokens.size();
      return fail(fmt::format("particle {} of {}", p + 1, count));
    }
    double v[kRotParticleTokens] = {};
    for (std::size_t k = 0; k < width; ++k) {
      if (k == 4 || k == 5) {
        continue;
      }
      if (!parseNumber(tokens[at + k], v[k])) {
        at += k;
        return fail(fmt::format("'{}' is not a number", tokens[at]));
      }
    }
    std::int64_t id = 0;
    std::int64_t tag = 0;
    if (!parseId(tokens[at + 4], id) || !parseId(tokens[at + 5], tag)) {
      at += 4;
      return fail("particle id and tag must be integers");
    }
    out.ids.push_back(id);
    out.group.push_back(static_cast<std::int32_t>(tag));
    out.positions.push_back({v[0], v[1], v[2]});
    out.radius.push_back(v[3]);
    out.velocities.push_back(
        {static_cast<float>(v[13]), static_cast<float>(v[14]), static_cast<float>(v[15])});
    out.extras[forceIndex].values.insert(out.extras[forceIndex].values.end(),
                                         {v[16], v[17], v[18]});
    at += width;
  }
  std::int64_t groups = 0;
  if (at >= tokens.size() || !parseId(tokens[at], groups) || groups < 0) {
    return fail("the number of bonded interaction groups");
  }
  ++at;
  for (std::int64_t g = 0; g < groups; ++g) {
    if (at + 1 >= tokens.size()) {
      at = tokens.size();
      return fail(fmt::format("bonded group {} of {}", g + 1, groups));
    }
    ++at;  // the group's type, e.g. RotBonded
    std::int64_t bonds = 0;
    if (!parseId(tokens[at], bonds) || bonds < 0) {
      return fail("the bond count of a bonded group");
    }
    ++at;
    for (std::int64_t b = 0; b < bonds; ++b) {
      SourceBond bond;
      if (at + 3 > tokens.size()) {
        at = tokens.size();
        return fail(fmt::format("bond {} of {}", b + 1, bonds));
      }
      if (!parseId(tokens[at], bond.first) || !parseId(tokens[at + 1], bond.second)) {
        return fail("bond particle ids must be integers");
      }
      out.bonds.push_back(bond);
      at += 3;
    }
  }
  return Status::ok();
}

Result<SourceStep> EsysSource::readStep(int index) {
  const auto& [step, path] = *std::next(m_masters.begin(), index);
  auto master = readMaster(path);
  if (!master) {
    return master.status();
  }
  SourceStep out;
  out.sourceStep = step;
  out.origin = path;
  out.time = static_cast<double>(master->step) * master->stepSize;
  out.timeKnown = true;
  const std::string folder = path.substr(0, path.size() - baseName(path).size());
  for (const std::string& worker : master->workers) {
    // Workers are named as the simulation saw them; look beside the master.
    CRACKVIS_RETURN_IF_ERROR(readWorker(folder + baseName(worker), out));
  }
  // Each worker's extras arrive as one array per worker: merge them.
  std::vector<dem::ExtraArray> merged;
  for (dem::ExtraArray& extra : out.extras) {
    auto same = std::find_if(merged.begin(), merged.end(),
                             [&](const dem::ExtraArray& m) { return m.name == extra.name; });
    if (same == merged.end()) {
      merged.push_back(std::move(extra));
    } else {
      same->values.insert(same->values.end(), extra.values.begin(), extra.values.end());
    }
  }
  out.extras = std::move(merged);
  return out;
}

}  // namespace

Result<std::unique_ptr<StepSource>> openEsys(const std::vector<std::string>& inputs) {
  auto source = std::make_unique<EsysSource>();
  auto master = [](const std::string& file) {
    const auto name = parseSnapshotName(file);
    return name && name->rank == 0;
  };
  CRACKVIS_RETURN_IF_ERROR(
      addInputs(inputs, master, [&](const std::string& file) { return source->add(file); }));
  CRACKVIS_RETURN_IF_ERROR(source->finish());
  return std::unique_ptr<StepSource>(std::move(source));
}

}  // namespace crackvis::importers
