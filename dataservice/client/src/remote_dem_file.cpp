#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <tuple>

#include <fmt/format.h>

#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/model.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dataservice {
namespace {

// The radii's path, the same in every layout.
const std::string& radiusPath() {
  static const std::string path = dem::datasetPath(dem::DemDataset::kRadius);
  return path;
}

// An optional dataset: absent is fine (false), present must be as the
// layout says.
Result<bool> optionalDataset(const FileDescription& description, dem::DemDataset id, int step,
                             const dem::LayoutSizes& sizes) {
  if (description.findDataset(demStepDatasetPath(description, id, step)) == nullptr) {
    return false;
  }
  CRACKVIS_RETURN_IF_ERROR(checkDemDataset(description, id, step, sizes));
  return true;
}

// The dataset of a per-particle extra array at `step`: per step if the step
// has it, else constant; its width (1 or 3) once dtype and shape are checked.
struct ExtraSlab {
  std::string path;
  int components = 1;
  bool matrix = false;    // stored [rows, k] rather than [rows]
  bool stepAxis = false;  // an appendable file's: one row per step
};

// `owner` is "particles" or "bonds"; `n` the rows (N or M).
Result<ExtraSlab> extraSlab(const FileDescription& description, const std::string& file,
                            const char* owner, const std::string& name, int step, std::uint64_t n) {
  const bool appendable = isAppendable(description);
  const std::string stepFolder = appendable ? std::string("/steps") : dem::stepGroupPath(step);
  const std::string perStep = fmt::format("{}/extra/{}/{}", stepFolder, owner, name);
  const std::string constant = fmt::format("/extra/{}/{}", owner, name);
  const DatasetInfo* dataset = description.findDataset(perStep);
  const bool stepAxis = appendable && dataset != nullptr;
  if (dataset == nullptr) {
    dataset = description.findDataset(constant);
  }
  if (dataset == nullptr) {
    std::vector<std::string> known;
    const std::string prefix = fmt::format("{}/extra/{}/", stepFolder, owner);
    for (const DatasetInfo& info : description.datasets) {
      for (const std::string& folder : {prefix, fmt::format("/extra/{}/", owner)}) {
        if (info.path.rfind(folder, 0) == 0) {
          known.push_back(info.path.substr(folder.size()));
        }
      }
    }
    return failedPrecondition(fmt::format(
        "{}: no per-{} extra array '{}' at step {} (the file has: {})", file,
        std::string_view(owner) == "bonds" ? "bond" : "particle", name, step,
        known.empty() ? std::string("none") : fmt::format("{}", fmt::join(known, ", "))));
  }
  std::vector<std::uint64_t> shape = dataset->shape;
  if (stepAxis) {
    if (shape.empty() || shape[0] <= static_cast<std::uint64_t>(step)) {
      return failedPrecondition(
          fmt::format("{}: dataset {} has shape {}, without a row for step {}", file, dataset->path,
                      dem::h5::formatDims(shape), step));
    }
    shape.erase(shape.begin());
  }
  const bool widthValid =
      shape.size() == 1 || (shape.size() == 2 && (shape[1] == 1 || shape[1] == 3));
  if (dataset->dtype != DataType::kFloat64 || shape.empty() || shape[0] != n || !widthValid) {
    return failedPrecondition(
        fmt::format("{}: dataset {} is {} {}, expected float64 [{}] or [{},3]", file, dataset->path,
                    dataset->dtypeName, dem::h5::formatDims(dataset->shape), n, n));
  }
  return ExtraSlab{dataset->path, shape.size() == 2 ? static_cast<int>(shape[1]) : 1,
                   shape.size() == 2, stepAxis};
}

// Every bond must join two existing particles (dem::checkBondEnds); `first`
// is the index of bonds[0] in the file's list (readStep checks the list
// chunk by chunk). A file that breaks it is FAILED_PRECONDITION, as every
// other problem of a file's content on this path.
Status checkBonds(std::span<const dem::Bond> bonds, std::int64_t particles, const std::string& file,
                  std::size_t first = 0) {
  if (Status ends = dem::checkBondEnds(bonds, particles, first); !ends) {
    return failedPrecondition(fmt::format("{}: {}", file, ends.message()));
  }
  return Status::ok();
}

// A bond list checked chunk by chunk as its bytes land in `bonds`, while
// they are still in the cache, rather than in one pass over megabytes after
// the last chunk. Chunks come in byte order; a bond split across two chunks
// is checked with the second.
class BondListCheck {
 public:
  BondListCheck(std::span<const dem::Bond> bonds, std::int64_t particles, const std::string& file)
      : m_bonds(bonds), m_particles(particles), m_file(file) {}
  Status arrived(std::uint64_t offset, std::uint64_t bytes) {
    const auto complete = static_cast<std::size_t>((offset + bytes) / sizeof(dem::Bond));
    const std::size_t first = m_checked;
    m_checked = complete;
    return checkBonds(m_bonds.subspan(first, complete - first), m_particles, m_file, first);
  }
  bool complete() const { return m_checked == m_bonds.size(); }

 private:
  std::span<const dem::Bond> m_bonds;
  std::int64_t m_particles;
  const std::string& m_file;
  std::size_t m_checked = 0;
};

}  // namespace

Result<RemoteDemFile> RemoteDemFile::open(const DataClient& client, const std::string& file,
                                          const OpenOptions& options) {
  // Sent before the Describe: its chunks arrive while the answer is checked.
  std::unique_ptr<DataClient::PendingRead> bonds;
  if (options.prefetchBondList) {
    std::vector<Hyperslab> slabs{Hyperslab::whole("/bonds/pairs")};
    if (options.prefetchRadii) {
      slabs.push_back(Hyperslab::whole(radiusPath()));
    }
    bonds = std::make_unique<DataClient::PendingRead>(client.startRead(file, slabs));
  }
  const auto describing = std::chrono::steady_clock::now();
  auto description = client.describe(file);
  if (!description) {
    return description.status();
  }
  const std::chrono::duration<double, std::milli> described =
      std::chrono::steady_clock::now() - describing;
  auto failed = [&](const Status& status) {
    return status.isOk() ? status
                         : Status(status.code(), fmt::format("{}: {}", file, status.message()));
  };
  auto dimension = dem::checkRootAttributes(demRootAttributes(*description));
  if (!dimension) {
    return failed(dimension.status());
  }
  RemoteDemFile remote;
  remote.m_client = client;
  remote.m_file = file;
  remote.m_describeMs = described.count();
  remote.m_dimension = *dimension;
  remote.m_appendable = isAppendable(*description);
  if (const GroupInfo* root = description->findGroup("/")) {
    if (const AttributeInfo* unit = root->findAttribute(dem::kTimeUnitAttribute)) {
      const auto* text = std::get_if<std::string>(&unit->value);
      remote.m_timeInIterations = text != nullptr && *text == dem::kTimeInIterations;
    }
  }
  // N and M from the datasets that carry them, as the local reader does.
  dem::LayoutSizes sizes;
  CRACKVIS_RETURN_IF_ERROR(
      failed(checkDemDataset(*description, dem::DemDataset::kRadius, 0, sizes)));
  sizes.particles = static_cast<std::int64_t>(description->findDataset(radiusPath())->shape[0]);
  CRACKVIS_RETURN_IF_ERROR(
      failed(checkDemDataset(*description, dem::DemDataset::kPairs, 0, sizes)));
  sizes.bonds = static_cast<std::int64_t>(description->findDataset("/bonds/pairs")->shape[0]);
  for (const StepEntry& step : description->steps) {
    for (dem::DemDataset id : {dem::DemDataset::kPositions, dem::DemDataset::kBondState}) {
      CRACKVIS_RETURN_IF_ERROR(failed(checkDemDataset(*description, id, step.index, sizes)));
    }
  }
  remote.m_particles = sizes.particles;
  remote.m_bonds = sizes.bonds;
  remote.m_description = std::make_shared<const FileDescription>(std::move(*description));
  remote.m_prefetchedBonds = std::move(bonds);
  remote.m_radiiAskedFor = options.prefetchBondList && options.prefetchRadii;
  CRACKVIS_RETURN_IF_ERROR(remote.readWritingFlag());
  return remote;
}

// The attribute alone: the local reader takes it only with an index that
// validates whole, so on a damaged index the two may differ; either answer
// is a decomposition the view may use (an unknown one is decided anew).
dem::CellDecomposition RemoteDemFile::recordedDecomposition() const {
  const GroupInfo* index = m_description->findGroup(dem::kSpatialIndexGroup);
  const AttributeInfo* recorded =
      index != nullptr ? index->findAttribute("decomposition") : nullptr;
  const auto* name = recorded != nullptr ? std::get_if<std::string>(&recorded->value) : nullptr;
  return name != nullptr ? dem::decompositionNamed(*name) : dem::CellDecomposition::kUnknown;
}

Status RemoteDemFile::takePrefetchedBonds() {
  if (!m_prefetchedBonds) {
    return Status::ok();
  }
  const std::unique_ptr<DataClient::PendingRead> pending = std::move(m_prefetchedBonds);
  const auto m = static_cast<std::uint64_t>(m_bonds);
  const auto n = static_cast<std::uint64_t>(m_particles);
  std::vector<dem::Bond> bonds(static_cast<std::size_t>(m));
  std::vector<double> radii;  // sized when its slab comes
  std::array<bool, 2> arrived{};
  BondListCheck check(bonds, m_particles, m_file);
  const Status received = pending->receive(
      [&](const DataClient::SlabHeader& slab) -> Result<std::byte*> {
        if (slab.index == 1) {  // the radii, asked for with the list
          if (slab.dtype != DataType::kFloat64 || slab.shape != std::vector<std::uint64_t>{n}) {
            return failedPrecondition(
                fmt::format("{}: {} arrived as {} [{}], expected float64 [{}]", m_file,
                            radiusPath(), dataTypeName(slab.dtype), fmt::join(slab.shape, ","), n));
          }
          arrived[1] = true;
          radii.resize(static_cast<std::size_t>(n));
          return reinterpret_cast<std::byte*>(radii.data());
        }
        if (slab.dtype != DataType::kInt32 || slab.shape != std::vector<std::uint64_t>{m, 2}) {
          return failedPrecondition(
              fmt::format("{}: /bonds/pairs arrived as {} [{}], expected int32 [{},2]", m_file,
                          dataTypeName(slab.dtype), fmt::join(slab.shape, ","), m));
        }
        arrived[0] = true;
        return reinterpret_cast<std::byte*>(bonds.data());
      },
      [&](std::size_t slab, std::uint64_t offset, std::uint64_t bytes) {
        return slab == 0 ? check.arrived(offset, bytes) : Status::ok();
      });
  switch (received.code()) {
    case StatusCode::kOk:
      break;
    case StatusCode::kResourceExhausted:  // a stream limit refused it
    case StatusCode::kDeadlineExceeded:   // the call time limit cut it
    case StatusCode::kCancelled:
    case StatusCode::kUnavailable:
      // Read again when needed (with the step, or alone); a list that is
      // wrong is an error.
      return Status::ok();
    default:
      return received;
  }
  if ((!arrived[0] && m != 0) || !check.complete() || (m_radiiAskedFor && !arrived[1] && n != 0)) {
    return internalError(
        fmt::format("{}: /bonds/pairs or {} arrived incomplete", m_file, radiusPath()));
  }
  m_bondList = std::make_shared<std::vector<dem::Bond>>(std::move(bonds));
  if (m_radiiAskedFor) {
    m_prefetchedRadii = std::move(radii);
  }
  return Status::ok();
}

Status RemoteDemFile::checkStep(int step) const {
  return dem::checkStepInRange(m_file, step, stepCount());
}

Result<std::vector<dem::Bond>> RemoteDemFile::toBonds(const TypedArray& array) const {
  if (array.dtype != DataType::kInt32 ||
      array.elementCount() != 2 * static_cast<std::uint64_t>(m_bonds)) {
    return failedPrecondition(fmt::format("{}: /bonds/pairs arrived as {} with {} values", m_file,
                                          dataTypeName(array.dtype), array.elementCount()));
  }
  std::vector<dem::Bond> bonds(static_cast<size_t>(m_bonds));
  if (!bonds.empty()) {
    std::memcpy(bonds.data(), array.bytes.data(), array.bytes.size());
  }
  CRACKVIS_RETURN_IF_ERROR(checkBonds(bonds, m_particles, m_file));
  return bonds;
}

Result<std::vector<dem::Vec3>> RemoteDemFile::toPositions(const TypedArray& array,
                                                          std::uint64_t expected) const {
  if (array.dtype != DataType::kFloat64 || array.elementCount() != 3 * expected) {
    return failedPrecondition(fmt::format("{}: {} arrived as {} with {} values, expected {}",
                                          m_file, array.dataset, dataTypeName(array.dtype),
                                          array.elementCount(), 3 * expected));
  }
  std::vector<dem::Vec3> positions(static_cast<size_t>(expected));
  if (!positions.empty()) {
    std::memcpy(positions.data(), array.bytes.data(), array.bytes.size());
  }
  return positions;
}

Result<std::vector<std::uint8_t>> RemoteDemFile::toBondState(const TypedArray& array) const {
  auto values = array.values<std::uint8_t>();
  if (!values) {
    return values.status();
  }
  if (values->size() != static_cast<size_t>(m_bonds)) {
    return failedPrecondition(fmt::format("{}: {} has {} values, expected M = {}", m_file,
                                          array.dataset, values->size(), m_bonds));
  }
  return values;
}

Status RemoteDemFile::loadBonds() {
  CRACKVIS_RETURN_IF_ERROR(takePrefetchedBonds());
  if (!m_bondList) {
    auto arrays = m_client->read(m_file, {Hyperslab::whole("/bonds/pairs")});
    if (!arrays) {
      return arrays.status();
    }
    auto bonds = toBonds(arrays->front());
    if (!bonds) {
      return bonds.status();
    }
    m_bondList = std::make_shared<std::vector<dem::Bond>>(std::move(*bonds));
  }
  return Status::ok();
}

Result<std::shared_ptr<const std::vector<dem::Bond>>> RemoteDemFile::bonds() {
  if (m_bondsTaken) {
    return failedPrecondition(fmt::format("{}: the bond list was handed over", m_file));
  }
  CRACKVIS_RETURN_IF_ERROR(loadBonds());
  return std::shared_ptr<const std::vector<dem::Bond>>(m_bondList);
}

Result<std::vector<dem::Bond>> RemoteDemFile::takeBonds() {
  if (m_bondsTaken) {
    return failedPrecondition(fmt::format("{}: the bond list was handed over", m_file));
  }
  CRACKVIS_RETURN_IF_ERROR(loadBonds());
  // 8 bytes a bond: 475 MB at 1e7 particles, not to be copied when not shared.
  std::vector<dem::Bond> bonds;
  if (m_bondList.use_count() == 1) {
    bonds = std::move(*m_bondList);
  } else {
    bonds = *m_bondList;
  }
  m_bondList.reset();
  m_bondsTaken = true;
  return bonds;
}

Result<std::vector<std::int32_t>> RemoteDemFile::breakSteps() const {
  auto present = optionalDataset(*m_description, dem::DemDataset::kBreakStep, 0, sizes());
  if (!present) {
    return present.status();
  }
  if (!*present) {
    return std::vector<std::int32_t>{};
  }
  auto arrays = m_client->read(m_file, {Hyperslab::whole("/bonds/break_step")});
  if (!arrays) {
    return arrays.status();
  }
  return arrays->front().values<std::int32_t>();
}

Result<std::vector<double>> RemoteDemFile::radii() {
  CRACKVIS_RETURN_IF_ERROR(takePrefetchedBonds());
  if (m_prefetchedRadii) {
    std::vector<double> radii = std::move(*m_prefetchedRadii);
    m_prefetchedRadii.reset();
    return radii;
  }
  auto arrays = m_client->read(m_file, {Hyperslab::whole(radiusPath())});
  if (!arrays) {
    return arrays.status();
  }
  return arrays->front().values<double>();
}

Result<RemoteStep> RemoteDemFile::readStep(int step, StepExtras extras) {
  const bool prefetched = m_prefetchedBonds != nullptr;
  auto result = readStepOnce(step, extras);
  // A server that allows one stream refuses the step's Read while the
  // prefetched list's is open; the list is taken by then (and its slot free
  // once the client has it), so the step is asked for once more.
  if (!result && prefetched && result.status().code() == StatusCode::kResourceExhausted) {
    return readStepOnce(step, std::move(extras));
  }
  return result;
}

Result<RemoteStep> RemoteDemFile::readStepOnce(int step, StepExtras extras) {
  CRACKVIS_RETURN_IF_ERROR(checkStep(step));
  const auto n = static_cast<std::uint64_t>(m_particles);
  const auto m = static_cast<std::uint64_t>(m_bonds);
  // The optional arrays are looked up only when asked for: the usual view
  // pays nothing for them.
  Result<bool> withVelocities = false;
  if (extras.velocities) {
    withVelocities = optionalDataset(*m_description, dem::DemDataset::kVelocities, step, sizes());
    if (!withVelocities) {
      return withVelocities.status();
    }
  }
  Result<bool> withForce = false;
  if (extras.bondForce) {
    withForce = optionalDataset(*m_description, dem::DemDataset::kBondForce, step, sizes());
    if (!withForce) {
      return withForce.status();
    }
  }
  const std::string& positionsPath =
      demStepDatasetPath(*m_description, dem::DemDataset::kPositions, step);
  std::vector<Hyperslab> slabs = {
      stepSlab(positionsPath, step, {n, 3}),
      stepSlab(demStepDatasetPath(*m_description, dem::DemDataset::kBondState, step), step, {m})};
  const bool withBonds = !m_bondList && !m_prefetchedBonds && !m_bondsTaken;
  const std::size_t bondsSlab = withBonds ? slabs.size() : SIZE_MAX;
  if (withBonds) {
    slabs.push_back(Hyperslab::whole("/bonds/pairs"));
  }
  const bool readVelocities = *withVelocities;
  const bool readForce = *withForce;
  if (readVelocities) {
    slabs.push_back(stepSlab(demStepDatasetPath(*m_description, dem::DemDataset::kVelocities, step),
                             step, {n, 3}));
  }
  if (readForce) {
    slabs.push_back(
        stepSlab(demStepDatasetPath(*m_description, dem::DemDataset::kBondForce, step), step, {m}));
  }
  // Extra arrays, per particle then per bond: (slab, rows, output).
  struct ExtraRead {
    ExtraSlab slab;
    std::uint64_t rows;
    std::vector<double>* values;
    int* components;
  };
  std::vector<ExtraRead> extraReads;
  RemoteStep result;
  for (const auto& [owner, name, rows, values, components] :
       {std::tuple{"particles", &extras.particleExtra, n, &result.particleExtra,
                   &result.particleExtraComponents},
        std::tuple{"bonds", &extras.bondExtra, m, &result.bondExtra,
                   &result.bondExtraComponents}}) {
    if (name->empty()) {
      continue;
    }
    auto found = extraSlab(*m_description, m_file, owner, *name, step, rows);
    if (!found) {
      return found.status();
    }
    extraReads.push_back({*found, rows, values, components});
    std::vector<std::uint64_t> row{rows};
    if (found->matrix) {
      row.push_back(static_cast<std::uint64_t>(found->components));
    }
    slabs.push_back(found->stepAxis ? stepSlab(found->path, step, row)
                                    : Hyperslab::whole(found->path));
  }
  // The request goes out first: the arrays below are allocated (3.5 MB for
  // cuboid A, page faults and zeroing included) while the server opens the
  // file and reads the first piece, not before the server hears of the call.
  auto pending = m_client->startRead(m_file, slabs);
  // A prefetched bond list is taken meanwhile (most of it has arrived).
  CRACKVIS_RETURN_IF_ERROR(takePrefetchedBonds());
  result.index = step;
  result.time = steps()[static_cast<size_t>(step)].time;
  result.positions.resize(n);
  result.bondState.resize(m);
  std::vector<dem::Bond> bonds(withBonds ? m : 0);
  // Straight into the typed arrays, once their dtype and shape are checked;
  // in the order of `slabs`.
  struct Expected {
    DataType dtype;
    std::vector<std::uint64_t> shape;
    std::byte* data;
    std::uint64_t elements() const {
      std::uint64_t count = 1;
      for (const std::uint64_t extent : shape) {
        count *= extent;
      }
      return count;
    }
  };
  std::vector<Expected> expected = {
      {DataType::kFloat64, stepShape({n, 3}),
       reinterpret_cast<std::byte*>(result.positions.data())},
      {DataType::kUInt8, stepShape({m}), reinterpret_cast<std::byte*>(result.bondState.data())}};
  if (withBonds) {
    expected.push_back({DataType::kInt32, {m, 2}, reinterpret_cast<std::byte*>(bonds.data())});
  }
  if (readVelocities) {
    result.velocities.resize(n);
    expected.push_back({DataType::kFloat32, stepShape({n, 3}),
                        reinterpret_cast<std::byte*>(result.velocities.data())});
  }
  if (readForce) {
    result.bondForce.resize(m);
    expected.push_back({DataType::kFloat32, stepShape({m}),
                        reinterpret_cast<std::byte*>(result.bondForce.data())});
  }
  for (const ExtraRead& read : extraReads) {
    const auto width = static_cast<std::uint64_t>(read.slab.components);
    *read.components = read.slab.components;
    read.values->resize(read.rows * width);
    std::vector<std::uint64_t> shape{read.rows};
    if (read.slab.matrix) {
      shape.push_back(width);
    }
    if (read.slab.stepAxis) {
      shape = stepShape(std::move(shape));
    }
    expected.push_back(
        {DataType::kFloat64, shape, reinterpret_cast<std::byte*>(read.values->data())});
  }
  std::vector<bool> arrived(slabs.size(), false);
  BondListCheck bondCheck(bonds, m_particles, m_file);
  CRACKVIS_RETURN_IF_ERROR(pending.receive(
      [&](const DataClient::SlabHeader& slab) -> Result<std::byte*> {
        const Expected& want = expected.at(slab.index);
        if (slab.dtype != want.dtype || slab.shape != want.shape) {
          return failedPrecondition(fmt::format(
              "{}: {} arrived as {} [{}], expected {} [{}]", m_file, slabs[slab.index].dataset,
              dataTypeName(slab.dtype), fmt::join(slab.shape, ","), dataTypeName(want.dtype),
              fmt::join(want.shape, ",")));
        }
        arrived[slab.index] = true;
        return want.data;
      },
      [&](std::size_t slab, std::uint64_t offset, std::uint64_t bytes) -> Status {
        return slab == bondsSlab ? bondCheck.arrived(offset, bytes) : Status::ok();
      }));
  for (size_t i = 0; i < slabs.size(); ++i) {
    if (!arrived[i] && expected[i].elements() != 0) {
      return internalError(fmt::format("{}: {} did not arrive", m_file, slabs[i].dataset));
    }
  }
  if (withBonds) {
    if (!bondCheck.complete()) {
      return internalError(fmt::format("{}: /bonds/pairs arrived incomplete", m_file));
    }
    m_bondList = std::make_shared<std::vector<dem::Bond>>(std::move(bonds));
  }
  return result;
}

Result<std::vector<dem::Vec3>> RemoteDemFile::positions(int step) const {
  CRACKVIS_RETURN_IF_ERROR(checkStep(step));
  const auto n = static_cast<std::uint64_t>(m_particles);
  auto arrays = m_client->read(
      m_file, {stepSlab(demStepDatasetPath(*m_description, dem::DemDataset::kPositions, step), step,
                        {n, 3})});
  if (!arrays) {
    return arrays.status();
  }
  return toPositions(arrays->front(), static_cast<std::uint64_t>(m_particles));
}

Result<std::vector<dem::Vec3>> RemoteDemFile::positions(int step, std::int64_t first,
                                                        std::int64_t count) const {
  CRACKVIS_RETURN_IF_ERROR(checkStep(step));
  const std::string path = demStepDatasetPath(*m_description, dem::DemDataset::kPositions, step);
  Hyperslab slab{path, {first, 0}, {count, 3}};
  if (m_appendable) {
    slab = {path, {step, first, 0}, {1, count, 3}};
  }
  auto arrays = m_client->read(m_file, {slab});
  if (!arrays) {
    return arrays.status();
  }
  return toPositions(arrays->front(), static_cast<std::uint64_t>(count));
}

Result<std::vector<std::uint8_t>> RemoteDemFile::bondState(int step) const {
  CRACKVIS_RETURN_IF_ERROR(checkStep(step));
  auto arrays = m_client->read(
      m_file, {stepSlab(demStepDatasetPath(*m_description, dem::DemDataset::kBondState, step), step,
                        {static_cast<std::uint64_t>(m_bonds)})});
  if (!arrays) {
    return arrays.status();
  }
  return toBondState(arrays->front());
}

}  // namespace crackvis::dataservice

namespace crackvis::dataservice {

Hyperslab RemoteDemFile::stepSlab(const std::string& path, int step,
                                  const std::vector<std::uint64_t>& rowShape) const {
  if (!m_appendable) {
    return Hyperslab::whole(path);
  }
  Hyperslab slab{path, {step}, {1}};
  for (const std::uint64_t extent : rowShape) {
    slab.start.push_back(0);
    slab.count.push_back(static_cast<std::int64_t>(extent));
  }
  return slab;
}

std::vector<std::uint64_t> RemoteDemFile::stepShape(std::vector<std::uint64_t> rowShape) const {
  if (m_appendable) {
    rowShape.insert(rowShape.begin(), 1);
  }
  return rowShape;
}

}  // namespace crackvis::dataservice

namespace crackvis::dataservice {
namespace {

std::string runIdOf(const FileDescription& description) {
  const GroupInfo* root = description.findGroup("/");
  const AttributeInfo* id = root != nullptr ? root->findAttribute(dem::kRunIdAttribute) : nullptr;
  const auto* text = id != nullptr ? std::get_if<std::string>(&id->value) : nullptr;
  return text != nullptr ? *text : std::string();
}

std::uint64_t rowsOf(const FileDescription& description, const char* dataset) {
  const DatasetInfo* info = description.findDataset(dataset);
  return info != nullptr && !info->shape.empty() ? info->shape[0] : 0;
}

}  // namespace

Result<bool> RemoteDemFile::refresh() {
  auto description = m_client->describe(m_file);
  if (!description) {
    return description.status();
  }
  const FileDescription& before = *m_description;
  const bool sameFile =
      runIdOf(*description) == runIdOf(before) && isAppendable(*description) == m_appendable &&
      rowsOf(*description, radiusPath().c_str()) == static_cast<std::uint64_t>(m_particles) &&
      rowsOf(*description, "/bonds/pairs") == static_cast<std::uint64_t>(m_bonds) &&
      description->steps.size() >= before.steps.size() &&
      (before.steps.empty() || description->steps.front().time == before.steps.front().time);
  if (!sameFile) {
    return failedPrecondition(fmt::format(
        "{}: the file was replaced while it was open (another run under the same name); open it "
        "again",
        m_file));
  }
  const dem::LayoutSizes layoutSizes = sizes();
  for (std::size_t k = before.steps.size(); k < description->steps.size(); ++k) {
    for (dem::DemDataset id : {dem::DemDataset::kPositions, dem::DemDataset::kBondState}) {
      if (Status valid = checkDemDataset(*description, id, static_cast<int>(k), layoutSizes);
          !valid) {
        return Status(valid.code(), fmt::format("{}: {}", m_file, valid.message()));
      }
    }
  }
  const bool grew = description->steps.size() > before.steps.size();
  m_description = std::make_shared<const FileDescription>(std::move(*description));
  CRACKVIS_RETURN_IF_ERROR(readWritingFlag());
  return grew;
}

Status RemoteDemFile::readWritingFlag() {
  m_beingWritten = false;
  if (!m_appendable || m_description->findDataset(dem::kStepsWritingPath) == nullptr) {
    return Status::ok();
  }
  auto arrays = m_client->read(m_file, {Hyperslab::whole(dem::kStepsWritingPath)});
  if (!arrays) {
    return arrays.status();
  }
  auto flag = arrays->front().values<std::int32_t>();
  if (!flag || flag->size() != 1) {
    return failedPrecondition(
        fmt::format("{}: {} is not one int32", m_file, dem::kStepsWritingPath));
  }
  m_beingWritten = flag->front() != 0;
  return Status::ok();
}

}  // namespace crackvis::dataservice

namespace crackvis::dataservice {

Result<std::vector<RemoteDemFile::ScalarSeries>> RemoteDemFile::stepScalars() const {
  const auto steps = static_cast<std::size_t>(stepCount());
  std::vector<ScalarSeries> series;
  if (!m_appendable) {
    std::map<std::string, std::size_t> index;  // name -> position in series
    for (std::size_t k = 0; k < steps; ++k) {
      const GroupInfo* group = m_description->findGroup(m_description->steps[k].group);
      if (group == nullptr) {
        continue;
      }
      for (const AttributeInfo& attribute : group->attributes) {
        const auto value = group->floatAttribute(attribute.name);
        if (attribute.name == "time" || !value) {
          continue;
        }
        auto [at, added] = index.try_emplace(attribute.name, series.size());
        if (added) {
          series.push_back({attribute.name,
                            std::vector<double>(steps, std::numeric_limits<double>::quiet_NaN())});
        }
        series[at->second].values[k] = *value;
      }
    }
    return series;
  }
  const std::string prefix = std::string(dem::kStepScalarsPath) + "/";
  std::vector<Hyperslab> slabs;
  for (const DatasetInfo& dataset : m_description->datasets) {
    if (dataset.path.rfind(prefix, 0) != 0 ||
        dataset.path.find('/', prefix.size()) != std::string::npos) {
      continue;
    }
    if (dataset.dtype != DataType::kFloat64 || dataset.shape.size() != 1 ||
        dataset.shape[0] < steps) {
      return failedPrecondition(
          fmt::format("{}: dataset {} is {} {}, expected float64 [{}] or longer", m_file,
                      dataset.path, dataset.dtypeName, dem::h5::formatDims(dataset.shape), steps));
    }
    series.push_back({dataset.path.substr(prefix.size()), {}});
    slabs.push_back({dataset.path, {0}, {static_cast<std::int64_t>(steps)}});
  }
  if (slabs.empty() || steps == 0) {
    for (ScalarSeries& s : series) {
      s.values.clear();
    }
    return series;
  }
  auto arrays = m_client->read(m_file, slabs);
  if (!arrays) {
    return arrays.status();
  }
  for (std::size_t i = 0; i < series.size(); ++i) {
    auto values = (*arrays)[i].values<double>();
    if (!values) {
      return values.status();
    }
    series[i].values = std::move(values).value();
  }
  return series;
}

}  // namespace crackvis::dataservice
