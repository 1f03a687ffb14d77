#include "crack_filter_state.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <unordered_map>

#include <fmt/format.h>
#include <unistd.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDataSetAttributes.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkInformation.h>
#include <vtkIntArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <crackvis/analysis/bond_normals.hpp>
#include <crackvis/analysis/opening.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/partition.hpp>

namespace crackvis::cracks::vtkadapter {
namespace {

// What each viewing array's memory belongs to. An entry lives exactly as
// long as VTK uses that memory: VTK calls releaseViewedMemory when the last
// array sharing the buffer lets it go (or moves its values elsewhere), and
// the entry's reference keeps the owner alive until then.
struct ViewedMemory {
  struct Views {
    std::shared_ptr<const void> owner;
    const std::type_info* ownerType = nullptr;  // what `owner` points to
    int buffers = 0;  // VTK buffers viewing the memory; each is released once
  };
  std::mutex mutex;
  std::unordered_map<const void*, Views> of;
};

ViewedMemory& viewed() {
  static ViewedMemory* registry = new ViewedMemory;  // outlives every array
  return *registry;
}

// VTK's free function of a viewing array's buffer. VTK keeps it for a
// buffer it later allocates itself (vtkBuffer::Allocate, after Initialize or
// SetNumberOfTuples on the array): such memory is VTK's malloc's, and freed.
// The owner is released outside the lock: releasing it may run its deleter.
void releaseViewedMemory(void* memory) {
  std::shared_ptr<const void> owner;
  {
    ViewedMemory& registry = viewed();
    const std::scoped_lock lock(registry.mutex);
    const auto found = registry.of.find(memory);
    if (found == registry.of.end()) {
      std::free(memory);
      return;
    }
    if (--found->second.buffers == 0) {
      owner = std::move(found->second.owner);
      registry.of.erase(found);
    }
  }
}

}  // namespace

vtkSmartPointer<vtkDataArray> viewingArray(int type, const char* name, const void* memory,
                                           vtkIdType tuples, int components,
                                           std::shared_ptr<const void> owner,
                                           const std::type_info& ownerType) {
  vtkSmartPointer<vtkDataArray> array;
  array.TakeReference(vtkDataArray::CreateDataArray(type));
  array->SetName(name);
  array->SetNumberOfComponents(components);
  if (memory == nullptr || tuples == 0) {
    return array;  // nothing to view
  }
  ViewedMemory& registry = viewed();
  const std::scoped_lock lock(registry.mutex);
  auto [entry, added] = registry.of.try_emplace(memory);
  ViewedMemory::Views& views = entry->second;
  const bool sameOwner = !views.owner.owner_before(owner) && !owner.owner_before(views.owner) &&
                         views.ownerType != nullptr && *views.ownerType == ownerType;
  if (!added && !sameOwner) {
    // Memory another owner's arrays still view: taking it over would
    // release that owner while they do. A copy is safe.
    array->SetNumberOfTuples(tuples);
    std::memcpy(array->GetVoidPointer(0), memory,
                static_cast<std::size_t>(tuples * components * array->GetDataTypeSize()));
    return array;
  }
  array->SetVoidArray(const_cast<void*>(memory), tuples * components, 0);
  array->SetArrayFreeFunction(releaseViewedMemory);
  // Registered once the array is made: it releases the memory once.
  if (added) {
    views.owner = std::move(owner);
    views.ownerType = &ownerType;
  }
  ++views.buffers;
  return array;
}

namespace {

vtkDataArray* cellArray(vtkPolyData* input, const char* name) {
  return input->GetCellData() != nullptr ? input->GetCellData()->GetArray(name) : nullptr;
}

// The n values of `array`, or none when it is missing or of another length.
void readInts(vtkDataArray* array, vtkIdType n, std::vector<std::int32_t>& out) {
  out.clear();
  if (array == nullptr || array->GetNumberOfTuples() != n) {
    return;
  }
  out.resize(static_cast<std::size_t>(n));
  for (vtkIdType i = 0; i < n; ++i) {
    out[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(array->GetComponent(i, 0));
  }
}

vtkSmartPointer<vtkCellArray> toCellArray(const PrimitiveList& list) {
  vtkNew<vtkTypeInt32Array> offsets;
  vtkNew<vtkTypeInt32Array> connectivity;
  offsets->SetNumberOfValues(static_cast<vtkIdType>(list.offsets.size()));
  std::memcpy(offsets->GetPointer(0), list.offsets.data(),
              list.offsets.size() * sizeof(std::int32_t));
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(list.connectivity.size()));
  if (!list.connectivity.empty()) {
    std::memcpy(connectivity->GetPointer(0), list.connectivity.data(),
                list.connectivity.size() * sizeof(std::int32_t));
  }
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  cells->SetData(offsets, connectivity);
  return cells;
}

vtkSmartPointer<vtkDataArray> toDataArray(const AttributeArray& array) {
  vtkSmartPointer<vtkDataArray> out;
  switch (array.type) {
    case AttributeType::kInt32:
      out = vtkSmartPointer<vtkIntArray>::New();
      break;
    case AttributeType::kFloat32:
      out = vtkSmartPointer<vtkFloatArray>::New();
      break;
    case AttributeType::kFloat64:
      out = vtkSmartPointer<vtkDoubleArray>::New();
      break;
  }
  out->SetName(array.name.c_str());
  out->SetNumberOfComponents(array.components);
  out->SetNumberOfTuples(static_cast<vtkIdType>(array.tupleCount()));
  for (std::size_t k = 0; k < array.values.size(); ++k) {
    out->SetVariantValue(static_cast<vtkIdType>(k), array.values[k]);
  }
  return out;
}

vtkSmartPointer<vtkPoints> toPoints(const std::vector<Vec3>& points) {
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(static_cast<vtkIdType>(points.size()));
  if (!points.empty()) {
    std::memcpy(coordinates->GetPointer(0), points.data(), points.size() * sizeof(Vec3));
  }
  auto result = vtkSmartPointer<vtkPoints>::New();
  result->SetData(coordinates);
  return result;
}

}  // namespace

StageLog::StageLog()
    : m_enabled(std::getenv("CRACKVIS_VTK_TIMINGS") != nullptr),
      m_start(std::chrono::steady_clock::now()),
      m_last(m_start) {}

void StageLog::mark(const char* stage) {
  const auto now = std::chrono::steady_clock::now();
  if (m_enabled) {
    m_stages += fmt::format(" {}_ms={:.1f}", stage,
                            std::chrono::duration<double, std::milli>(now - m_last).count());
  }
  m_last = now;
}

namespace {

// The process's resident and peak resident memory in MiB (/proc/self/status
// VmRSS, VmHWM); -1 where not known. Read for each stage line, so that the
// benchmarks see which update sets a rank's peak.
std::pair<double, double> residentMiB() {
  std::pair<double, double> out{-1.0, -1.0};
  std::FILE* status = std::fopen("/proc/self/status", "r");
  if (status == nullptr) {
    return out;
  }
  char line[256];
  while (std::fgets(line, sizeof line, status) != nullptr) {
    long kib = 0;
    if (std::sscanf(line, "VmRSS: %ld kB", &kib) == 1) {
      out.first = static_cast<double>(kib) / 1024.0;
    } else if (std::sscanf(line, "VmHWM: %ld kB", &kib) == 1) {
      out.second = static_cast<double>(kib) / 1024.0;
    }
  }
  std::fclose(status);
  return out;
}

}  // namespace

void StageLog::report(const char* what, double time, std::FILE* out) const {
  if (m_enabled) {
    const auto [rss, peak] = residentMiB();
    const auto sinceEpoch = [](std::chrono::steady_clock::time_point t) {
      return std::chrono::duration<double, std::milli>(t.time_since_epoch()).count();
    };
    const double total = std::chrono::duration<double, std::milli>(m_last - m_start).count();
    // start and end on the steady clock (CLOCK_MONOTONIC, as Python's
    // time.perf_counter): the time between updates' stages shows too.
    // The MPI rank as Open MPI or MPICH's launcher names it; "-" without one.
    const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
    rank = rank != nullptr ? rank : std::getenv("PMI_RANK");
    fmt::print(out,
               "crackvis-vtk-timings pid={} rank={} {} time={}{} total_ms={:.1f} start={:.1f} "
               "end={:.1f} rss_mib={:.0f} peak_mib={:.0f}\n",
               ::getpid(), rank != nullptr ? rank : "-", what, time, m_stages, total,
               sinceEpoch(m_start), sinceEpoch(m_last), rss, peak);
  }
}

CrackFilterState::CrackFilterState() = default;
CrackFilterState::~CrackFilterState() = default;

bool ArrayStamp::matches(vtkObject* object) const {
  return object != nullptr && object == m_object && object->GetMTime() == m_time;
}

void ArrayStamp::set(vtkObject* object) {
  m_object = object;
  m_time = object != nullptr ? object->GetMTime() : 0;
}

namespace {

// The positions, and whether every z is 0 (a 2D set).
bool readPositions(vtkPolyData* input, std::vector<Vec3>& positions) {
  const vtkIdType n = input->GetNumberOfPoints();
  positions.resize(static_cast<std::size_t>(n));
  vtkDoubleArray* data =
      n > 0 ? vtkDoubleArray::FastDownCast(input->GetPoints()->GetData()) : nullptr;
  if (data != nullptr && data->GetNumberOfComponents() == 3) {
    static_assert(sizeof(Vec3) == 3 * sizeof(double));
    // Vec3 is three doubles (asserted above), as the array holds them.
    std::memcpy(static_cast<void*>(positions.data()), data->GetPointer(0),
                positions.size() * sizeof(Vec3));
  } else {
    for (vtkIdType i = 0; i < n; ++i) {
      double p[3];
      input->GetPoint(i, p);
      positions[static_cast<std::size_t>(i)] = {p[0], p[1], p[2]};
    }
  }
  return std::all_of(positions.begin(), positions.end(), [](const Vec3& p) { return p.z == 0.0; });
}

// The bond states as 0 and 1.
void readStates(vtkDataArray* state, std::vector<std::uint8_t>& out) {
  const vtkIdType m = state->GetNumberOfTuples();
  out.resize(static_cast<std::size_t>(m));
  if (auto* bytes = vtkUnsignedCharArray::FastDownCast(state);
      bytes != nullptr && bytes->GetNumberOfComponents() == 1) {
    const unsigned char* values = bytes->GetPointer(0);
    for (vtkIdType b = 0; b < m; ++b) {
      out[static_cast<std::size_t>(b)] = values[b] != 0 ? 1 : 0;
    }
    return;
  }
  for (vtkIdType b = 0; b < m; ++b) {
    out[static_cast<std::size_t>(b)] = state->GetComponent(b, 0) != 0.0 ? 1 : 0;
  }
}

}  // namespace

bool CrackFilterState::readBonds(vtkCellArray* lines, vtkIdType n, std::vector<dem::Bond>& bonds,
                                 std::string& error) {
  bonds.reserve(static_cast<std::size_t>(lines->GetNumberOfCells()));
  const vtkIdType* ids = nullptr;
  vtkIdType count = 0;
  auto iterator = vtk::TakeSmartPointer(lines->NewIterator());
  for (iterator->GoToFirstCell(); !iterator->IsDoneWithTraversal(); iterator->GoToNextCell()) {
    iterator->GetCurrentCell(count, ids);
    if (count != 2 || ids[0] < 0 || ids[1] < 0 || ids[0] >= n || ids[1] >= n) {
      error = fmt::format("bond {} is not a line between two of the {} points", bonds.size(), n);
      return false;
    }
    bonds.push_back(
        {static_cast<dem::ParticleIndex>(ids[0]), static_cast<dem::ParticleIndex>(ids[1])});
  }
  return true;
}

void CrackFilterState::readRadius(vtkPolyData* input, vtkIdType n, double radiusDefault) {
  vtkDataArray* radius =
      input->GetPointData() != nullptr ? input->GetPointData()->GetArray("radius") : nullptr;
  if (m_radiusStamp.matches(radius) && m_radius.size() == static_cast<std::size_t>(n)) {
    return;
  }
  m_radiusStamp.set(nullptr);
  m_radius.assign(static_cast<std::size_t>(n), radiusDefault);
  if (radius != nullptr && radius->GetNumberOfTuples() == n) {
    for (vtkIdType i = 0; i < n; ++i) {
      m_radius[static_cast<std::size_t>(i)] = radius->GetComponent(i, 0);
    }
    m_radiusStamp.set(radius);
  }
}

void CrackFilterState::readBreakSteps(vtkPolyData* input, vtkIdType m) {
  vtkDataArray* breaks = cellArray(input, "break_step");
  if (m_breakStepStamp.matches(breaks) && m_breakStep.size() == static_cast<std::size_t>(m)) {
    return;
  }
  m_breakStepStamp.set(nullptr);
  m_breakStep.clear();
  if (breaks != nullptr && breaks->GetNumberOfTuples() == m) {
    readInts(breaks, m, m_breakStep);
    m_breakStepStamp.set(breaks);
  }
}

bool CrackFilterState::readLattice(vtkPolyData* input, double radiusDefault, std::string& error) {
  const vtkIdType n = input->GetNumberOfPoints();
  vtkCellArray* lines = input->GetLines();
  const vtkIdType m = lines != nullptr ? lines->GetNumberOfCells() : 0;
  vtkDataArray* state = cellArray(input, "bond_state");
  if (state == nullptr || state->GetNumberOfTuples() != input->GetNumberOfCells() ||
      input->GetNumberOfCells() != m) {
    error = fmt::format(
        "input needs one line per bond and cell data 'bond_state' with one value per "
        "line ({} lines, {} cells, {} bond states)",
        m, input->GetNumberOfCells(), state != nullptr ? state->GetNumberOfTuples() : 0);
    return false;
  }
  // The bonds as last read, checked against these points: the same lines
  // need no second look.
  const bool sameLines = m_graph != nullptr && m_linesStamp.matches(lines) &&
                         m_positions.size() == static_cast<std::size_t>(n);
  std::vector<dem::Bond> bonds;
  if (!sameLines && !readBonds(lines, n, bonds, error)) {
    return false;
  }
  const bool flat = readPositions(input, m_positions);
  readRadius(input, n, radiusDefault);
  readStates(state, m_state);
  m_force.clear();
  if (vtkDataArray* force = cellArray(input, "bond_force");
      force != nullptr && force->GetNumberOfTuples() == m) {
    m_force.resize(static_cast<std::size_t>(m));
    for (vtkIdType b = 0; b < m; ++b) {
      m_force[static_cast<std::size_t>(b)] = static_cast<float>(force->GetComponent(b, 0));
    }
  }
  readReference(input, n);
  readBreakSteps(input, m);
  if (sameLines) {
    return true;
  }
  m_linesStamp.set(nullptr);
  if (bonds != m_bonds || m_graph == nullptr) {
    dem::Lattice check;
    check.dimension = flat ? 2 : 3;
    check.radius = m_radius;
    check.bonds = bonds;
    check.strength.assign(bonds.size(), 0.0);
    if (Status valid = dem::validateLattice(check); !valid) {
      error = valid.message();
      return false;
    }
    m_bonds = std::move(bonds);
    m_dimension = check.dimension;
    m_extractor.reset();
    m_normals.reset();
    m_graph = std::make_unique<BondGraph>(static_cast<std::size_t>(n), m_bonds);
  }
  m_linesStamp.set(lines);
  return true;
}

void CrackFilterState::readReference(vtkPolyData* input, vtkIdType n) {
  vtkDataArray* reference = input->GetPointData() != nullptr
                                ? input->GetPointData()->GetArray(kReferencePositionArray)
                                : nullptr;
  if (m_referenceStamp.matches(reference) && m_reference.size() == static_cast<std::size_t>(n)) {
    return;
  }
  m_referenceStamp.set(nullptr);
  m_reference.clear();
  m_normals.reset();  // found in the old reference
  if (reference == nullptr || reference->GetNumberOfComponents() != 3 ||
      reference->GetNumberOfTuples() != n) {
    return;
  }
  m_referenceStamp.set(reference);
  m_reference.resize(static_cast<std::size_t>(n));
  for (vtkIdType i = 0; i < n; ++i) {
    double p[3];
    reference->GetTuple(i, p);
    m_reference[static_cast<std::size_t>(i)] = {p[0], p[1], p[2]};
  }
}

void addTriangulationArrays(std::shared_ptr<const Triangulation> triangulation,
                            vtkFieldData* field) {
  static_assert(sizeof(int) == sizeof(dem::ParticleIndex));
  static_assert(sizeof(triangulation->cells[0]) == 4 * sizeof(int) &&
                sizeof(triangulation->edges[0]) == 2 * sizeof(int));
  if (triangulation == nullptr || triangulation->cells.empty()) {
    return;
  }
  const auto cells = static_cast<vtkIdType>(triangulation->cells.size());
  const auto edges = static_cast<vtkIdType>(triangulation->edges.size());
  field->AddArray(viewingArray(VTK_INT, kTriangulationCellsArray, triangulation->cells.data(),
                               cells, 4, triangulation));
  if (edges > 0) {
    field->AddArray(viewingArray(VTK_INT, kTriangulationEdgesArray, triangulation->edges.data(),
                                 edges, 2, triangulation));
  } else {
    // Cells without edges cannot be; an empty array keeps the pair whole.
    auto none = vtkSmartPointer<vtkIntArray>::New();
    none->SetName(kTriangulationEdgesArray);
    none->SetNumberOfComponents(2);
    field->AddArray(none);
  }
}

std::shared_ptr<const Triangulation> viewedTriangulation(vtkDataArray* cells, vtkDataArray* edges) {
  // Only int arrays can view one (and asking another kind for its pointer
  // would copy its values).
  auto* cellInts = vtkIntArray::FastDownCast(cells);
  auto* edgeInts = vtkIntArray::FastDownCast(edges);
  if (cellInts == nullptr || edgeInts == nullptr || cellInts->GetNumberOfTuples() == 0 ||
      cellInts->GetNumberOfComponents() != 4 || edgeInts->GetNumberOfComponents() != 2) {
    return nullptr;
  }
  ViewedMemory& registry = viewed();
  const std::scoped_lock lock(registry.mutex);
  const auto found = registry.of.find(cellInts->GetPointer(0));
  if (found == registry.of.end() || found->second.ownerType == nullptr ||
      *found->second.ownerType != typeid(const Triangulation)) {
    return nullptr;
  }
  const auto triangulation = std::static_pointer_cast<const Triangulation>(found->second.owner);
  const bool same =
      static_cast<const void*>(cellInts->GetPointer(0)) == triangulation->cells.data() &&
      cellInts->GetNumberOfTuples() == static_cast<vtkIdType>(triangulation->cells.size()) &&
      edgeInts->GetNumberOfTuples() == static_cast<vtkIdType>(triangulation->edges.size()) &&
      (triangulation->edges.empty() ||
       static_cast<const void*>(edgeInts->GetPointer(0)) == triangulation->edges.data());
  return same ? triangulation : nullptr;
}

bool CrackFilterState::readPiece(vtkPolyData* input, ExtractOptions& options) {
  vtkDataArray* ghost = input->GetPointData()->GetArray(vtkDataSetAttributes::GhostArrayName());
  vtkDataArray* particles = input->GetPointData()->GetGlobalIds();
  vtkDataArray* bonds = input->GetCellData()->GetGlobalIds();
  vtkDataArray* centres = input->GetFieldData()->GetArray(kSpecimenCentresArray);
  vtkDataArray* largest = input->GetFieldData()->GetArray(kLargestRadiusArray);
  vtkDataArray* decomposition = input->GetFieldData()->GetArray(kDecompositionArray);
  const vtkIdType n = input->GetNumberOfPoints();
  const vtkIdType m = input->GetNumberOfCells();
  if (ghost == nullptr || particles == nullptr || bonds == nullptr || centres == nullptr ||
      largest == nullptr || decomposition == nullptr || ghost->GetNumberOfTuples() != n ||
      particles->GetNumberOfTuples() != n || bonds->GetNumberOfTuples() != m ||
      centres->GetNumberOfValues() != 6) {
    m_owned.clear();
    m_globalParticle = nullptr;
    m_globalBond = nullptr;
    m_components.clear();
    m_intactComponents.clear();
    return false;
  }
  // A piece keeps its particles and bonds from step to step.
  if (!m_ghostStamp.matches(ghost) || m_owned.size() != static_cast<std::size_t>(n)) {
    m_owned.resize(static_cast<std::size_t>(n));
    for (vtkIdType i = 0; i < n; ++i) {
      m_owned[static_cast<std::size_t>(i)] = ghost->GetComponent(i, 0) == 0.0 ? 1 : 0;
    }
    m_ghostStamp.set(ghost);
  }
  // The whole set's ids are read where the input holds them, for the crack's
  // primitives only (toWholeSet): a copy was 8 bytes per particle and bond.
  m_globalParticle = particles;
  m_globalBond = bonds;
  double box[6];
  for (int k = 0; k < 6; ++k) {
    box[k] = centres->GetComponent(0, k);
  }
  options.specimenCentres = Box{{box[0], box[1], box[2]}, {box[3], box[4], box[5]}};
  options.specimenLargestRadius = largest->GetComponent(0, 0);
  options.ownerParticles = true;
  if (options.decomposition == Decomposition::kAuto) {
    options.decomposition = decomposition->GetComponent(0, 0) == 0.0
                                ? Decomposition::kLattice
                                : Decomposition::kTriangulation;
  }
  readTriangulation(input, options);
  readInts(input->GetPointData()->GetArray(kComponentArray), n, m_components);
  readInts(input->GetPointData()->GetArray(kIntactComponentArray), n, m_intactComponents);
  return true;
}

void CrackFilterState::readTriangulation(vtkPolyData* input, ExtractOptions& options) {
  vtkDataArray* cells = input->GetFieldData()->GetArray(kTriangulationCellsArray);
  vtkDataArray* edges = input->GetFieldData()->GetArray(kTriangulationEdgesArray);
  if (cells == nullptr || edges == nullptr || cells->GetNumberOfComponents() != 4 ||
      edges->GetNumberOfComponents() != 2) {
    m_triangulation.reset();
    return;
  }
  // The reader adds the same arrays every step: unchanged, nothing to read.
  const std::pair<vtkMTimeType, vtkMTimeType> stamp{cells->GetMTime(), edges->GetMTime()};
  if (m_triangulation != nullptr && stamp == m_triangulationStamp) {
    options.triangulation = m_triangulation;
    return;
  }
  m_triangulationStamp = stamp;
  // The reader's arrays view its triangulation: shared, not copied.
  std::shared_ptr<const Triangulation> given = viewedTriangulation(cells, edges);
  if (given == nullptr) {
    given = copyTriangulation(cells, edges);
  }
  // The same cells as last step keep the extractor (and its increments).
  if (m_triangulation == nullptr ||
      (m_triangulation != given &&
       (m_triangulation->cells != given->cells || m_triangulation->edges != given->edges))) {
    m_triangulation = std::move(given);
  }
  options.triangulation = m_triangulation;
}

std::shared_ptr<const Triangulation> CrackFilterState::copyTriangulation(
    vtkDataArray* cells, vtkDataArray* edges) const {
  auto copy = std::make_shared<Triangulation>();
  copy->dimension = m_dimension;
  copy->cells.resize(static_cast<std::size_t>(cells->GetNumberOfTuples()));
  for (vtkIdType c = 0; c < cells->GetNumberOfTuples(); ++c) {
    for (int k = 0; k < 4; ++k) {
      copy->cells[static_cast<std::size_t>(c)][static_cast<std::size_t>(k)] =
          static_cast<dem::ParticleIndex>(cells->GetComponent(c, k));
    }
  }
  copy->edges.resize(static_cast<std::size_t>(edges->GetNumberOfTuples()));
  for (vtkIdType e = 0; e < edges->GetNumberOfTuples(); ++e) {
    copy->edges[static_cast<std::size_t>(e)] = {
        static_cast<dem::ParticleIndex>(edges->GetComponent(e, 0)),
        static_cast<dem::ParticleIndex>(edges->GetComponent(e, 1))};
  }
  return copy;
}

// Keeps the piece's own primitives and gives their particle and bond ids in
// the whole set's numbering, as a single-process run outputs them.
void CrackFilterState::toWholeSet(CrackMesh& mesh) const {
  keepOwned(mesh, m_owned);
  auto remap = [](AttributeArray& array, vtkDataArray* global) {
    const vtkIdType count = global != nullptr ? global->GetNumberOfTuples() : 0;
    for (double& id : array.values) {
      const bool known = id >= 0.0 && id < static_cast<double>(count);
      id = known ? global->GetComponent(static_cast<vtkIdType>(id), 0) : id;
    }
  };
  for (auto* arrays : {&mesh.cellData, &mesh.pointData}) {
    for (AttributeArray& array : *arrays) {
      if (array.name == "bond_id" || array.name == "first_broken_bond") {
        remap(array, m_globalBond);
      } else if (array.name == "particle_id") {
        remap(array, m_globalParticle);
      }
    }
  }
}

bool CrackFilterState::run(vtkPolyData* input, Method method, const ExtractOptions& requested,
                           double radiusDefault, CrackMesh& mesh, std::string& error) {
  m_stages = StageLog{};
  if (input == nullptr) {
    error = "no input";
    return false;
  }
  // An empty piece (an MPI rank the reader gave no particles) has no crack;
  // the state of the pieces that do is kept.
  if (input->GetNumberOfPoints() == 0 && input->GetNumberOfCells() == 0) {
    mesh = CrackMesh{};
    return true;
  }
  if (!readLattice(input, radiusDefault, error)) {
    return false;
  }
  m_stages.mark("lattice");
  ExtractOptions options = requested;
  const bool piece = readPiece(input, options);
  if (m_extractor == nullptr || method != m_method || options != m_options) {
    m_method = method;
    m_options = options;
    m_extractor = makeExtractor(method, *m_graph, m_dimension, options);
  }
  m_stages.mark("piece");
  // The reference configuration comes as point data (the crackvis-dem
  // reader gives the first step's positions): with it, local Voronoi faces
  // are material surfaces and a triangulation is made in the reference, as
  // `crackvis extract` does; without it, in the first step the filter sees.
  const StepInput step{m_positions, m_state,     m_radius,     m_force,
                       m_breakStep, m_reference, m_components, m_intactComponents};
  if (Status status = m_extractor->extract(step, mesh); !status) {
    error = status.message();
    return false;
  }
  m_stages.mark("extract");
  // Opening and slip against the reference, as `crackvis report` and the
  // render server measure them; a piece measures with its ghost layer,
  // before it keeps its own. The normals are kept across steps, as the
  // render server keeps them: a step finds those of its new breaks (found
  // anew every step, they were most of a step's update at 10^6 particles).
  // The opening arrays need no components.
  if (!m_reference.empty()) {
    if (m_normals == nullptr) {
      m_normals = std::make_unique<analysis::BondNormals>(m_dimension);
    }
    m_normals->update(m_bonds, m_state, m_reference);
    analysis::appendOpeningArrays(
        mesh, analysis::measureOpening(mesh, CrackComponents{}, m_bonds, m_reference, m_positions,
                                       {}, m_normals.get()));
  }
  m_stages.mark("opening");
  if (piece) {
    toWholeSet(mesh);
  }
  m_stages.mark("whole_set");
  return true;
}

void CrackFilterState::reportStages(vtkPolyData* input, const char* what) {
  m_stages.mark("output");
  vtkInformation* info = input != nullptr ? input->GetInformation() : nullptr;
  const bool timed = info != nullptr && info->Has(vtkDataObject::DATA_TIME_STEP()) != 0;
  m_stages.report(what, timed ? info->Get(vtkDataObject::DATA_TIME_STEP()) : 0.0);
}

void toPolyData(const CrackMesh& mesh, vtkPolyData* output) {
  output->Initialize();
  output->SetPoints(toPoints(mesh.points));
  PrimitiveList vertices;
  for (std::int32_t v : mesh.vertices) {
    vertices.add({v});
  }
  output->SetVerts(toCellArray(vertices));
  output->SetLines(toCellArray(mesh.lines));
  output->SetPolys(toCellArray(mesh.polygons));
  for (const AttributeArray& array : mesh.cellData) {
    output->GetCellData()->AddArray(toDataArray(array));
  }
  for (const AttributeArray& array : mesh.pointData) {
    output->GetPointData()->AddArray(toDataArray(array));
  }
}

void toUnstructuredGrid(const CrackMesh& mesh, vtkUnstructuredGrid* output) {
  output->Initialize();
  output->SetPoints(toPoints(mesh.points));
  // Cells in the order of the cell data: vertices, lines, polygons, volumes.
  PrimitiveList all;
  vtkNew<vtkUnsignedCharArray> types;
  for (std::int32_t v : mesh.vertices) {
    all.add({v});
    types->InsertNextValue(1);  // VTK_VERTEX
  }
  auto append = [&](const PrimitiveList& list, auto typeOf) {
    for (std::size_t k = 0; k < list.size(); ++k) {
      all.addRange(list.connectivity.begin() + list.offsets[k],
                   list.connectivity.begin() + list.offsets[k + 1]);
      types->InsertNextValue(typeOf(k));
    }
  };
  append(mesh.lines, [](std::size_t) { return std::uint8_t{4}; });     // VTK_POLY_LINE
  append(mesh.polygons, [](std::size_t) { return std::uint8_t{7}; });  // VTK_POLYGON
  append(mesh.volumeCells, [&](std::size_t k) { return mesh.volumeCellTypes[k]; });
  output->SetCells(types, toCellArray(all));
  for (const AttributeArray& array : mesh.cellData) {
    output->GetCellData()->AddArray(toDataArray(array));
  }
  for (const AttributeArray& array : mesh.pointData) {
    output->GetPointData()->AddArray(toDataArray(array));
  }
}

}  // namespace crackvis::cracks::vtkadapter
