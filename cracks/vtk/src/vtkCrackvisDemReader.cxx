#include "vtkCrackvisDemReader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>

#include <vtkAbstractArray.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataSetAttributes.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnsignedCharArray.h>

#include "crack_filter_state.h"
#include "crackvis_vtk_conversion.h"
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/partition.hpp>
#include <crackvis/cracks/triangulation.hpp>
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::cracks::vtkadapter {

// A lattice's arrays as the output carries them, the same at every step.
struct StaticArrays {
  vtkSmartPointer<vtkDoubleArray> reference;              // the first step's positions
  vtkSmartPointer<vtkCellArray> lines;                    // the bonds
  std::vector<vtkSmartPointer<vtkAbstractArray>> points;  // radius, ids, groups, extras
  std::vector<vtkSmartPointer<vtkAbstractArray>> cells;   // break steps, strength, flags, extras
};

// The arrays of a step whose output VTK has let go, kept for the next read
// (DemFileReader::readStep's `recycled`): reading into fresh memory and
// copying it into fresh VTK arrays put a third of a 10^7 rank's samples
// over its later steps in the kernel's zeroing of new pages (most in the
// first step after the first update). One step's worth is kept, the
// larger one: a piece cut from a whole read returns piece-sized arrays,
// while the next whole read needs whole-sized ones.
class StepSpares {
 public:
  void put(dem::StepState&& state) {
    const std::scoped_lock lock(m_mutex);
    if (!m_spare || state.positions.capacity() >= m_spare->positions.capacity()) {
      m_spare = std::move(state);
    }
  }
  dem::StepState take() {
    const std::scoped_lock lock(m_mutex);
    dem::StepState out = m_spare ? std::move(*m_spare) : dem::StepState{};
    m_spare.reset();
    return out;
  }

 private:
  std::mutex m_mutex;
  std::optional<dem::StepState> m_spare;
};

// The open file and its time-independent part, kept while the file name
// stays the same: stepping through time reads only the step.
struct DemReaderCache {
  std::string fileName;
  std::optional<dem::DemFileReader> reader;
  dem::Lattice lattice;
  std::vector<std::int32_t> breakSteps;
  std::vector<double> times;
  std::vector<dem::Vec3> reference;  // the first step's positions
  bool loaded = false;               // lattice, breakSteps and reference read
  // The piece last asked for (piece of pieces, with pieces > 1) and what it
  // holds, kept while the request stays the same: every step of a piece
  // holds the same particles and bonds, so the filters stay incremental.
  int piece = 0;
  int pieces = 1;
  double ghostBonds = -1.0;  // the request's ghost width in longest bonds; -1: none yet
  // Whether the piece was read through the file's spatial index (only its
  // rows; a step reads only its rows), or cut from the whole set.
  bool indexed = false;
  Piece part;
  // The piece's lattice, break steps and first positions, held only while
  // the piece is prepared: pieceArrays keeps them after.
  dem::Lattice pieceLattice;
  std::vector<std::int32_t> pieceBreakSteps;
  std::vector<dem::Vec3> pieceReference;
  dem::Bounds box;             // the whole specimen's reference box
  int axis = 0;                // the axis the pieces are cut across
  double largestRadius = 0.0;  // the whole set's
  int decomposition = -1;      // of the whole set: 0 lattice, 1 triangulation; -1 not decided
  std::optional<Triangulation> triangulation;  // the whole set's, when it is triangulated
  // Its cells and edges in the piece, while prepared: the piece's field
  // arrays then hold them (addTriangulationArrays).
  std::shared_ptr<const Triangulation> pieceTriangulation;
  std::vector<std::int32_t> pieceIntactComponents;
  // A triangulated piece read through the index: which of its particles the
  // whole set's intact bonds join, at any step.
  std::optional<BreakForest> forest;
  // The arrays every step of the piece shares (ghost marks, global ids, the
  // whole set's box, decomposition and triangulation), made once and added
  // by reference: an unchanged array tells the filters nothing changed.
  vtkSmartPointer<vtkPolyData> pieceData;
  // The time-independent arrays of the whole set and of the piece: made
  // once, not at every step. Making them again at every step was a large
  // part of a step's time at 10^7 particles (the bond lines alone are 24
  // bytes a bond), spent faulting in fresh pages.
  std::optional<StaticArrays> wholeArrays;
  std::optional<StaticArrays> pieceArrays;
  // A live file's writer records the step of each bond it breaks as it
  // commits the step: the break steps read before new steps are stale.
  bool breakStepsStale = false;
  // Shared with the step arrays VTK still holds, which return to it.
  std::shared_ptr<StepSpares> spares = std::make_shared<StepSpares>();
};

namespace {

// The step shown at time `t`: the last one saved at or before it (the first
// when `t` comes before every step), as ParaView's "snap to time steps" does.
int stepAt(const std::vector<double>& times, double t) {
  const auto after = std::upper_bound(times.begin(), times.end(), t + 1e-12 * std::abs(t));
  return after == times.begin() ? 0 : static_cast<int>(after - times.begin()) - 1;
}

// `values` as a named VTK array of `components`; null when empty.
template <typename VtkArray, typename Value>
vtkSmartPointer<VtkArray> makeArray(const char* name, const std::vector<Value>& values,
                                    int components = 1) {
  if (values.empty()) {
    return nullptr;
  }
  auto array = vtkSmartPointer<VtkArray>::New();
  array->SetName(name);
  array->SetNumberOfComponents(components);
  array->SetNumberOfTuples(static_cast<vtkIdType>(values.size() / components));
  std::copy(values.begin(), values.end(), array->GetPointer(0));
  return array;
}

template <typename VtkArray, typename Value>
void addArray(vtkFieldData* data, const char* name, const std::vector<Value>& values,
              int components = 1) {
  if (auto array = makeArray<VtkArray>(name, values, components)) {
    data->AddArray(array);
  }
}

vtkSmartPointer<vtkDoubleArray> toArray(const std::vector<dem::Vec3>& positions) {
  auto coordinates = vtkSmartPointer<vtkDoubleArray>::New();
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(static_cast<vtkIdType>(positions.size()));
  static_assert(sizeof(dem::Vec3) == 3 * sizeof(double));
  if (!positions.empty()) {
    std::memcpy(coordinates->GetPointer(0), positions.data(), positions.size() * sizeof(dem::Vec3));
  }
  return coordinates;
}

vtkSmartPointer<vtkCellArray> toLines(const std::vector<dem::Bond>& bonds) {
  vtkNew<vtkIdTypeArray> offsets;
  vtkNew<vtkIdTypeArray> connectivity;
  offsets->SetNumberOfTuples(static_cast<vtkIdType>(bonds.size() + 1));
  connectivity->SetNumberOfTuples(static_cast<vtkIdType>(2 * bonds.size()));
  for (std::size_t b = 0; b <= bonds.size(); ++b) {
    offsets->SetValue(static_cast<vtkIdType>(b), static_cast<vtkIdType>(2 * b));
  }
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    connectivity->SetValue(static_cast<vtkIdType>(2 * b), bonds[b].first);
    connectivity->SetValue(static_cast<vtkIdType>(2 * b + 1), bonds[b].second);
  }
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  lines->SetData(offsets, connectivity);
  return lines;
}

template <typename VtkArray, typename Value>
void keep(std::vector<vtkSmartPointer<vtkAbstractArray>>& arrays, const char* name,
          const std::vector<Value>& values, int components = 1) {
  if (auto array = makeArray<VtkArray>(name, values, components)) {
    arrays.push_back(array);
  }
}

// In the order the output has always carried them.
StaticArrays makeStaticArrays(const dem::Lattice& lattice,
                              const std::vector<std::int32_t>& breakSteps,
                              const std::vector<dem::Vec3>& reference) {
  StaticArrays fixed;
  // The filters make local Voronoi faces and triangulations in it, as
  // `crackvis extract` does in the file's first step.
  fixed.reference = toArray(reference);
  fixed.reference->SetName(kReferencePositionArray);
  fixed.lines = toLines(lattice.bonds);
  keep<vtkDoubleArray>(fixed.points, "radius", lattice.radius);
  keep<vtkTypeInt64Array>(fixed.points, "particle_id", lattice.particleId);
  keep<vtkIntArray>(fixed.points, "particle_group", lattice.particleGroup);
  keep<vtkIntArray>(fixed.cells, "break_step", breakSteps);
  keep<vtkDoubleArray>(fixed.cells, "strength", lattice.strength);
  keep<vtkUnsignedCharArray>(fixed.cells, "bond_flags", lattice.bondFlags);
  for (const dem::ExtraArray& extra : lattice.extras) {
    keep<vtkDoubleArray>(extra.owner == dem::ExtraOwner::kParticles ? fixed.points : fixed.cells,
                         extra.name.c_str(), extra.values, extra.components);
  }
  return fixed;
}

void addFieldData(int step, const dem::StepState& state, vtkPolyData* output) {
  vtkFieldData* field = output->GetFieldData();
  vtkNew<vtkIntArray> index;
  index->SetName("step");
  index->InsertNextValue(step);
  field->AddArray(index);
  vtkNew<vtkDoubleArray> time;
  time->SetName("time");
  time->InsertNextValue(state.time);
  field->AddArray(time);
  for (const dem::StepScalar& scalar : state.scalars) {
    vtkNew<vtkDoubleArray> value;
    value->SetName(scalar.name.c_str());
    value->InsertNextValue(scalar.value);
    field->AddArray(value);
  }
}

// The time-independent part and the reference configuration, read once (a
// piece read through the file's spatial index does without).
Status loadLattice(DemReaderCache& cache) {
  if (cache.loaded) {
    return Status::ok();
  }
  auto lattice = cache.reader->readLattice();
  if (!lattice) {
    return lattice.status();
  }
  auto breakSteps = cache.reader->readBreakSteps();
  if (!breakSteps) {
    return breakSteps.status();
  }
  auto first = cache.reader->readStep(0);
  if (!first) {
    return first.status();
  }
  cache.lattice = std::move(*lattice);
  cache.breakSteps = std::move(*breakSteps);
  cache.reference = std::move(first->positions);
  cache.loaded = true;
  return Status::ok();
}

// The step's per-step extra arrays, viewing `state`'s memory.
void viewExtras(const std::shared_ptr<dem::StepState>& state, vtkPolyData* output) {
  for (const dem::ExtraArray& extra : state->extras) {
    if (extra.values.empty() || extra.components <= 0) {
      continue;
    }
    vtkFieldData* data = extra.owner == dem::ExtraOwner::kParticles
                             ? static_cast<vtkFieldData*>(output->GetPointData())
                             : static_cast<vtkFieldData*>(output->GetCellData());
    data->AddArray(viewingArray(VTK_DOUBLE, extra.name.c_str(), extra.values.data(),
                                static_cast<vtkIdType>(extra.rows()), extra.components, state));
  }
}

// A step's output: the time-independent arrays by reference, the step's own
// arrays (positions, velocities, bond states and forces, extras) viewing its
// memory (no copy), which goes back to `spares` once VTK has let go of every
// array viewing it.
void fill(const StaticArrays& fixed, int step, dem::StepState&& read,
          const std::shared_ptr<StepSpares>& spares, vtkPolyData* output) {
  static_assert(sizeof(dem::Vec3) == 3 * sizeof(double));
  const std::weak_ptr<StepSpares> back = spares;
  const std::shared_ptr<dem::StepState> state(new dem::StepState(std::move(read)),
                                              [back](dem::StepState* done) {
                                                if (const auto keep = back.lock()) {
                                                  keep->put(std::move(*done));
                                                }
                                                delete done;
                                              });
  vtkNew<vtkPoints> points;
  points->SetData(viewingArray(VTK_DOUBLE, "Points", state->positions.data(),
                               static_cast<vtkIdType>(state->positions.size()), 3, state));
  output->SetPoints(points);
  output->SetLines(fixed.lines);
  vtkPointData* pointData = output->GetPointData();
  pointData->AddArray(fixed.reference);
  for (const auto& array : fixed.points) {
    pointData->AddArray(array);
  }
  static_assert(sizeof(state->velocities[0]) == 3 * sizeof(float));
  if (!state->velocities.empty()) {
    pointData->AddArray(viewingArray(VTK_FLOAT, "velocity", state->velocities.data(),
                                     static_cast<vtkIdType>(state->velocities.size()), 3, state));
  }
  vtkCellData* cells = output->GetCellData();
  if (!state->bondState.empty()) {
    cells->AddArray(viewingArray(VTK_UNSIGNED_CHAR, "bond_state", state->bondState.data(),
                                 static_cast<vtkIdType>(state->bondState.size()), 1, state));
  }
  if (!state->bondForce.empty()) {
    cells->AddArray(viewingArray(VTK_FLOAT, "bond_force", state->bondForce.data(),
                                 static_cast<vtkIdType>(state->bondForce.size()), 1, state));
  }
  for (const auto& array : fixed.cells) {
    cells->AddArray(array);
  }
  viewExtras(state, output);
  addFieldData(step, *state, output);
}

// The rows of `values` (rows of `width` values) at `rows`; empty stays empty.
template <typename T, typename Index>
std::vector<T> pick(const std::vector<T>& values, const std::vector<Index>& rows,
                    std::size_t width = 1) {
  std::vector<T> out;
  if (values.empty()) {
    return out;
  }
  out.reserve(rows.size() * width);
  for (Index row : rows) {
    const auto first =
        values.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(row) * width);
    out.insert(out.end(), first, first + static_cast<std::ptrdiff_t>(width));
  }
  return out;
}

std::vector<dem::ExtraArray> pickExtras(const std::vector<dem::ExtraArray>& extras,
                                        const Piece& part) {
  std::vector<dem::ExtraArray> out = extras;
  for (dem::ExtraArray& extra : out) {
    const auto width = static_cast<std::size_t>(extra.components);
    extra.values = extra.owner == dem::ExtraOwner::kParticles
                       ? pick(extra.values, part.particles, width)
                       : pick(extra.values, part.bonds, width);
  }
  return out;
}

// How `crackvis extract` divides the whole set (decided once per file, on
// the whole bond graph: a piece's graph, cut at its ghost layer, might not
// look like a lattice), and its triangulation when it is no lattice.
Status decideDecomposition(DemReaderCache& cache) {
  if (cache.decomposition < 0) {
    const BondGraph graph(cache.lattice.particleCount(), cache.lattice.bonds);
    cache.decomposition = isLatticeGraph(graph, cache.lattice.dimension) ? 0 : 1;
  }
  if (cache.decomposition == 1 && !cache.triangulation) {
    auto made = triangulate(cache.reference, cache.lattice.radius, cache.lattice.dimension);
    if (!made) {
      return made.status();
    }
    cache.triangulation = std::move(*made);
  }
  return Status::ok();
}

// The whole set's triangulation in piece indices: the cells and edges whose
// nodes the piece holds, and the intact packing's components.
void restrictTriangulation(DemReaderCache& cache) {
  auto restricted = std::make_shared<Triangulation>();
  restricted->dimension = cache.triangulation->dimension;
  restricted->weighted = cache.triangulation->weighted;
  std::vector<std::int32_t> local(cache.reference.size(), -1);
  for (std::size_t k = 0; k < cache.part.particles.size(); ++k) {
    local[static_cast<std::size_t>(cache.part.particles[k])] = static_cast<std::int32_t>(k);
  }
  auto held = [&](dem::ParticleIndex i) {
    return i < 0 || local[static_cast<std::size_t>(i)] >= 0;
  };
  auto toLocal = [&](dem::ParticleIndex i) {
    return i < 0 ? -1 : local[static_cast<std::size_t>(i)];
  };
  for (const auto& cell : cache.triangulation->cells) {
    if (std::all_of(cell.begin(), cell.end(), held)) {
      restricted->cells.push_back(
          {toLocal(cell[0]), toLocal(cell[1]), toLocal(cell[2]), toLocal(cell[3])});
    }
  }
  for (const dem::Bond& edge : cache.triangulation->edges) {
    if (held(edge.first) && held(edge.second)) {
      restricted->edges.push_back({toLocal(edge.first), toLocal(edge.second)});
    }
  }
  // Held as long as the piece is shown: no slack.
  restricted->cells.shrink_to_fit();
  restricted->edges.shrink_to_fit();
  cache.pieceTriangulation = std::move(restricted);
  cache.pieceIntactComponents = pick(
      connectedComponents(cache.reference.size(), cache.lattice.bonds, {}), cache.part.particles);
}

template <typename Index>
void addPieceMarks(vtkDataSetAttributes* attributes, const std::vector<Index>& global,
                   const std::vector<std::uint8_t>& owned, bool points) {
  vtkNew<vtkIdTypeArray> ids;
  ids->SetName(points ? "GlobalPointIds" : "GlobalCellIds");
  ids->SetNumberOfTuples(static_cast<vtkIdType>(global.size()));
  vtkNew<vtkUnsignedCharArray> ghost;
  ghost->SetName(vtkDataSetAttributes::GhostArrayName());
  ghost->SetNumberOfTuples(static_cast<vtkIdType>(global.size()));
  const auto duplicate =
      static_cast<unsigned char>(points ? int{vtkDataSetAttributes::DUPLICATEPOINT}
                                        : int{vtkDataSetAttributes::DUPLICATECELL});
  for (std::size_t k = 0; k < global.size(); ++k) {
    ids->SetValue(static_cast<vtkIdType>(k), global[k]);
    ghost->SetValue(static_cast<vtkIdType>(k), owned[k] != 0 ? 0 : duplicate);
  }
  attributes->SetGlobalIds(ids);
  attributes->AddArray(ghost);
}

// The local Voronoi domain of a piece: the whole specimen's box, but across
// the cut only as far as the piece's particles reach. The cells that make
// the piece's own faces lie within a bond or two of its slab and are closed
// by their neighbours either way; the cells at the ghost layer's far edge
// lack neighbours, and clipped at the whole box they would reach across the
// specimen, and their validation would search every particle of the piece
// (at 10^7 particles, minutes per rank).
dem::Bounds pieceDomain(const DemReaderCache& cache) {
  dem::Bounds box = cache.box;
  if (cache.pieceReference.empty()) {
    return box;
  }
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (const dem::Vec3& p : cache.pieceReference) {
    lo = std::min(lo, dem::axisCoordinate(p, cache.axis));
    hi = std::max(hi, dem::axisCoordinate(p, cache.axis));
  }
  double* boxLo[3] = {&box.lo.x, &box.lo.y, &box.lo.z};
  double* boxHi[3] = {&box.hi.x, &box.hi.y, &box.hi.z};
  *boxLo[cache.axis] = std::max(*boxLo[cache.axis], lo);
  *boxHi[cache.axis] = std::min(*boxHi[cache.axis], hi);
  return box;
}

// What makes the piece's filters equal the whole set's: ghost marks, global
// ids, and the whole set's box (across the cut, the piece's: pieceDomain),
// largest radius and decomposition.
void addPieceData(const DemReaderCache& cache, vtkPolyData* output) {
  addPieceMarks(output->GetPointData(), cache.part.particles, cache.part.owned, true);
  addPieceMarks(output->GetCellData(), cache.part.bonds, cache.part.bondOwned, false);
  const dem::Bounds box = pieceDomain(cache);
  const std::vector<double> centres{box.lo.x, box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z};
  vtkFieldData* field = output->GetFieldData();
  addArray<vtkDoubleArray>(field, kSpecimenCentresArray, centres, 6);
  addArray<vtkDoubleArray>(field, kLargestRadiusArray, std::vector<double>{cache.largestRadius});
  addArray<vtkIntArray>(field, kDecompositionArray, std::vector<int>{cache.decomposition});
  addTriangulationArrays(cache.pieceTriangulation, field);
  addArray<vtkIntArray>(output->GetPointData(), kIntactComponentArray, cache.pieceIntactComponents);
}

// Piece `piece` of `pieces` through the file's spatial index: only the
// piece's rows are read, now and at every step. False when the file has no
// index this can use (cracks::readIndexedPiece).
Result<bool> readPieceThroughIndex(DemReaderCache& cache, int piece, int pieces,
                                   double ghostBonds) {
  // Nothing of the piece asked for before may outlive it.
  cache.pieceTriangulation.reset();
  cache.pieceIntactComponents.clear();
  cache.forest.reset();
  auto indexed = readIndexedPiece(*cache.reader, piece, pieces, ghostBonds);
  if (!indexed) {
    return indexed.status();
  }
  if (!*indexed) {
    return false;
  }
  IndexedPiece& read = **indexed;
  cache.part = std::move(read.part);
  cache.pieceLattice = std::move(read.lattice);
  cache.pieceBreakSteps = std::move(read.breakSteps);
  cache.pieceReference = std::move(read.reference);
  cache.box = read.index.box;
  cache.axis = read.index.axis;
  cache.largestRadius = read.index.largestRadius;
  cache.decomposition = read.index.decomposition == dem::CellDecomposition::kTriangulation ? 1 : 0;
  if (read.triangulated) {
    cache.pieceTriangulation =
        std::make_shared<const Triangulation>(std::move(read.triangulated->triangulation));
    cache.forest = std::move(read.triangulated->forest);
    cache.pieceIntactComponents = componentsAt(*cache.forest, -1);
  }
  return true;
}

// Piece `piece` of `pieces` cut from the whole set, read whole.
Status cutPieceFromWholeSet(DemReaderCache& cache, int piece, int pieces, double ghostBonds) {
  CRACKVIS_RETURN_IF_ERROR(loadLattice(cache));
  CRACKVIS_RETURN_IF_ERROR(decideDecomposition(cache));
  const double width = ghostBonds * longestBond(cache.reference, cache.lattice.bonds);
  cache.part = partitionPiece(cache.reference, cache.lattice.bonds, piece, pieces, width,
                              cache.triangulation ? &*cache.triangulation : nullptr);
  const Piece& part = cache.part;
  const dem::Lattice& whole = cache.lattice;
  dem::Lattice& lattice = cache.pieceLattice;
  lattice.dimension = whole.dimension;
  lattice.radius = pick(whole.radius, part.particles);
  lattice.bonds = part.localBonds;
  lattice.strength = pick(whole.strength, part.bonds);
  lattice.particleId = pick(whole.particleId, part.particles);
  lattice.particleGroup = pick(whole.particleGroup, part.particles);
  lattice.bondFlags = pick(whole.bondFlags, part.bonds);
  lattice.extras = pickExtras(whole.extras, part);
  cache.pieceBreakSteps = pick(cache.breakSteps, part.bonds);
  cache.pieceReference = pick(cache.reference, part.particles);
  cache.box = dem::boundingBox(cache.reference);
  cache.axis = dem::sliceAxis(cache.reference);
  const auto& radius = whole.radius;
  cache.largestRadius = radius.empty() ? 0.0 : *std::max_element(radius.begin(), radius.end());
  if (cache.triangulation) {
    restrictTriangulation(cache);
  }
  return Status::ok();
}

// Piece `piece` of `pieces` (once per request: the partition depends only
// on the reference configuration): through the file's spatial index when it
// has one, else cut from the whole set. True when it was read now.
Result<bool> preparePiece(DemReaderCache& cache, int piece, int pieces, double ghostBonds) {
  if (cache.pieces == pieces && cache.piece == piece && cache.ghostBonds == ghostBonds) {
    return false;
  }
  // No piece is held until this one is: a failed read leaves nothing that a
  // later request for the previous piece would take for whole.
  cache.pieces = 0;
  auto indexed = readPieceThroughIndex(cache, piece, pieces, ghostBonds);
  if (!indexed) {
    return indexed.status();
  }
  cache.indexed = *indexed;
  if (!cache.indexed) {
    CRACKVIS_RETURN_IF_ERROR(cutPieceFromWholeSet(cache, piece, pieces, ghostBonds));
  }
  cache.piece = piece;
  cache.pieces = pieces;
  cache.ghostBonds = ghostBonds;
  cache.pieceData = vtkSmartPointer<vtkPolyData>::New();
  addPieceData(cache, cache.pieceData);
  cache.pieceArrays =
      makeStaticArrays(cache.pieceLattice, cache.pieceBreakSteps, cache.pieceReference);
  // The arrays hold them now: a rank keeps one copy of its piece (a random
  // packing's cells and edges are a tenth of a rank's memory).
  cache.pieceTriangulation.reset();
  cache.pieceIntactComponents = {};
  cache.pieceLattice = dem::Lattice{};
  cache.pieceBreakSteps = {};
  cache.pieceReference = {};
  return true;
}

void replaceCellArray(StaticArrays& arrays, vtkSmartPointer<vtkAbstractArray> array) {
  for (auto& kept : arrays.cells) {
    if (std::strcmp(kept->GetName(), array->GetName()) == 0) {
      kept = array;
      return;
    }
  }
  arrays.cells.push_back(array);
}

// The break steps again, after a live file's writer added steps: the whole
// set's, and the piece's rows of them and its forest, unless the piece was
// read after the steps were added (`pieceCurrent`).
Status refreshBreakSteps(DemReaderCache& cache, bool pieceCurrent) {
  if (cache.loaded) {
    auto breakSteps = cache.reader->readBreakSteps();
    if (!breakSteps) {
      return breakSteps.status();
    }
    cache.breakSteps = std::move(*breakSteps);
    auto array = makeArray<vtkIntArray>("break_step", cache.breakSteps);
    if (array && cache.wholeArrays) {
      replaceCellArray(*cache.wholeArrays, array);
    }
  }
  if (pieceCurrent) {
    cache.breakStepsStale = false;
    return Status::ok();
  }
  if (cache.pieceArrays && !cache.part.bonds.empty()) {
    std::vector<std::int32_t> rows;
    if (cache.indexed) {
      auto read = cache.reader->readBreakStepRows(cache.part.bonds);
      if (!read) {
        return read.status();
      }
      rows = std::move(*read);
    } else {
      rows = pick(cache.breakSteps, cache.part.bonds);
    }
    replaceCellArray(*cache.pieceArrays, makeArray<vtkIntArray>("break_step", rows));
  }
  if (cache.forest) {
    // Bonds broken since it was built were read as never breaking.
    auto forest = readBreakForest(*cache.reader, cache.part.particles);
    if (!forest) {
      return forest.status();
    }
    cache.forest = std::move(*forest);
  }
  cache.breakStepsStale = false;
  return Status::ok();
}

dem::StepState pieceState(const dem::StepState& whole, const Piece& part) {
  dem::StepState state;
  state.time = whole.time;
  state.scalars = whole.scalars;
  state.positions = pick(whole.positions, part.particles);
  state.velocities = pick(whole.velocities, part.particles);
  state.bondState = pick(whole.bondState, part.bonds);
  state.bondForce = pick(whole.bondForce, part.bonds);
  state.extras = pickExtras(whole.extras, part);
  return state;
}

// The piece's shared arrays into this step's output.
void sharePieceData(vtkPolyData* piece, vtkPolyData* output) {
  for (auto [from, to] :
       {std::pair<vtkFieldData*, vtkFieldData*>{piece->GetPointData(), output->GetPointData()},
        {piece->GetCellData(), output->GetCellData()},
        {piece->GetFieldData(), output->GetFieldData()}}) {
    for (int k = 0; k < from->GetNumberOfArrays(); ++k) {
      to->AddArray(from->GetAbstractArray(k));
    }
  }
  output->GetPointData()->SetGlobalIds(piece->GetPointData()->GetGlobalIds());
  output->GetCellData()->SetGlobalIds(piece->GetCellData()->GetGlobalIds());
}

// The step's components of the whole set, for a triangulated piece.
void addComponents(const DemReaderCache& cache, const dem::StepState& whole, vtkPolyData* output) {
  if (!cache.triangulation) {
    return;
  }
  addArray<vtkIntArray>(
      output->GetPointData(), kComponentArray,
      pick(connectedComponents(cache.reference.size(), cache.lattice.bonds, whole.bondState),
           cache.part.particles));
}

// The step's components of the whole set, for a triangulated piece read
// through the index: from its forest, without the whole set's bonds.
void addIndexedComponents(const DemReaderCache& cache, int step, vtkPolyData* output) {
  if (cache.forest) {
    addArray<vtkIntArray>(output->GetPointData(), kComponentArray,
                          componentsAt(*cache.forest, step));
  }
}

}  // namespace

}  // namespace crackvis::cracks::vtkadapter

using crackvis::cracks::vtkadapter::DemReaderCache;

vtkStandardNewMacro(vtkCrackvisDemReader);

vtkCrackvisDemReader::vtkCrackvisDemReader() : Cache(std::make_unique<DemReaderCache>()) {
  this->SetNumberOfInputPorts(0);
}

vtkCrackvisDemReader::~vtkCrackvisDemReader() {
  this->SetFileName(nullptr);
}

void vtkCrackvisDemReader::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName != nullptr ? this->FileName : "(none)") << "\n";
  os << indent << "GhostWidth: " << this->GhostWidth << "\n";
}

int vtkCrackvisDemReader::CanReadFile(const char* fileName) {
  if (fileName == nullptr) {
    return 0;
  }
  return crackvis::dem::DemFileReader::open(fileName).isOk() ? 1 : 0;
}

int vtkCrackvisDemReader::RequestInformation(vtkInformation*, vtkInformationVector**,
                                             vtkInformationVector* outputVector) {
  if (this->FileName == nullptr || *this->FileName == '\0') {
    vtkErrorMacro("no FileName: name a crackvis-dem file (.h5)");
    return 0;
  }
  DemReaderCache& cache = *this->Cache;
  if (cache.fileName != this->FileName || !cache.reader) {
    cache = DemReaderCache{};
    auto reader = crackvis::dem::DemFileReader::open(this->FileName);
    if (!reader) {
      vtkErrorMacro(<< reader.status().message());
      return 0;
    }
    if (reader->stepCount() == 0) {
      vtkErrorMacro(<< this->FileName << ": the file holds no complete step");
      return 0;
    }
    for (const crackvis::dem::StepInfo& step : reader->info().steps) {
      cache.times.push_back(step.time);
    }
    cache.reader.emplace(std::move(*reader));
    cache.fileName = this->FileName;
  } else if (cache.reader->info().stepLayout == crackvis::dem::StepLayout::kAppendable &&
             cache.reader->info().beingWritten) {
    // A live file: the steps its writer committed since (ParaView's Reload
    // Files, or any update of the pipeline's information).
    if (crackvis::Status refreshed = cache.reader->refreshSteps(); !refreshed) {
      vtkErrorMacro(<< refreshed.message());
      return 0;
    }
    const std::size_t before = cache.times.size();
    cache.times.clear();
    for (const crackvis::dem::StepInfo& step : cache.reader->info().steps) {
      cache.times.push_back(step.time);
    }
    cache.breakStepsStale = cache.breakStepsStale || cache.times.size() != before;
  }
  vtkInformation* out = outputVector->GetInformationObject(0);
  out->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), cache.times.data(),
           static_cast<int>(cache.times.size()));
  const double range[2] = {cache.times.front(), cache.times.back()};
  out->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  out->Set(vtkAlgorithm::CAN_HANDLE_PIECE_REQUEST(), 1);
  return 1;
}

int vtkCrackvisDemReader::RequestData(vtkInformation*, vtkInformationVector**,
                                      vtkInformationVector* outputVector) {
  vtkInformation* out = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(out);
  DemReaderCache& cache = *this->Cache;
  if (!cache.reader) {
    return 0;  // RequestInformation reported why
  }
  const int piece = out->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
                        ? out->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
                        : 0;
  const int pieces = out->Has(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES())
                         ? out->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES())
                         : 1;
  if (piece < 0 || piece >= pieces) {
    return 1;  // no such piece: empty
  }
  namespace adapter = crackvis::cracks::vtkadapter;
  adapter::StageLog stages;
  const int step =
      out->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
          ? adapter::stepAt(cache.times,
                            out->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
          : 0;
  // A piece read now through the index: its break steps and forest are the
  // file's as it is (one cut from the whole set picks from the whole set's,
  // which may be older).
  bool pieceCurrent = false;
  if (pieces > 1) {
    auto prepared = adapter::preparePiece(cache, piece, pieces, this->GhostWidth);
    if (!prepared) {
      vtkErrorMacro(<< this->FileName << ": " << prepared.status().message());
      return 0;
    }
    pieceCurrent = *prepared && cache.indexed;
  } else if (crackvis::Status loaded = adapter::loadLattice(cache); !loaded) {
    vtkErrorMacro(<< loaded.message());
    return 0;
  } else if (!cache.wholeArrays) {
    cache.wholeArrays = adapter::makeStaticArrays(cache.lattice, cache.breakSteps, cache.reference);
  }
  if (cache.breakStepsStale) {
    if (crackvis::Status refreshed = adapter::refreshBreakSteps(cache, pieceCurrent); !refreshed) {
      vtkErrorMacro(<< refreshed.message());
      return 0;
    }
  }
  stages.mark("prepare");
  // A piece read through the index reads only its rows of the step.
  auto state = pieces > 1 && cache.indexed
                   ? cache.reader->readStepRows(step, cache.part.particles, cache.part.bonds,
                                                cache.spares->take())
                   : cache.reader->readStep(step, cache.spares->take());
  if (!state) {
    vtkErrorMacro(<< state.status().message());
    return 0;
  }
  stages.mark("read");
  const double time = state->time;
  if (pieces == 1) {
    adapter::fill(*cache.wholeArrays, step, std::move(*state), cache.spares, output);
  } else {
    if (cache.indexed) {
      adapter::addIndexedComponents(cache, step, output);
      adapter::fill(*cache.pieceArrays, step, std::move(*state), cache.spares, output);
    } else {
      adapter::addComponents(cache, *state, output);
      adapter::fill(*cache.pieceArrays, step, adapter::pieceState(*state, cache.part), cache.spares,
                    output);
      cache.spares->put(std::move(*state));  // the whole read's arrays, for the next
    }
    adapter::sharePieceData(cache.pieceData, output);
  }
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), time);
  stages.mark("fill");
  stages.report(pieces > 1 ? "reader-piece" : "reader", time);
  return 1;
}
