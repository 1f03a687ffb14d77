#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>

#include <fmt/format.h>

#include <crackvis/analysis/opening.hpp>
#include <crackvis/common/elapsed.hpp>
#include <crackvis/common/exception_boundary.hpp>
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/bond_mapping.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/scene/scene_pipeline.hpp>
#include <crackvis/scene_model/scene_content.hpp>

namespace crackvis::scene {
namespace {

// A description's step in a file of `stepCount` steps: -1 is the last; any
// other step is itself, so that checkStepInRange refuses one the file lacks
// (other negative ones too) naming the file's steps, rather than another
// step being shown.
int resolveStep(std::int64_t step, int stepCount) {
  if (step == -1) {
    return stepCount - 1;
  }
  return static_cast<int>(std::clamp<std::int64_t>(step, std::numeric_limits<int>::min(),
                                                   std::numeric_limits<int>::max()));
}

// A step source whose exceptions become errors. Its reads run on the owner's
// thread and on the step cache's prefetch thread, where an exception (a
// library throwing on data it should have refused) would end the process.
class GuardedSource final : public source::StepSource {
 public:
  explicit GuardedSource(std::unique_ptr<source::StepSource> inner) : m_inner(std::move(inner)) {}
  const std::string& file() const override { return m_inner->file(); }
  const dem::Lattice& lattice() const override { return m_inner->lattice(); }
  int stepCount() const override { return m_inner->stepCount(); }
  const std::vector<std::int32_t>& breakSteps() const override { return m_inner->breakSteps(); }
  bool timeInIterations() const override { return m_inner->timeInIterations(); }
  bool appendable() const override { return m_inner->appendable(); }
  bool beingWritten() const override { return m_inner->beingWritten(); }
  double describeMs() const override { return m_inner->describeMs(); }
  dem::CellDecomposition recordedDecomposition() const override {
    return m_inner->recordedDecomposition();
  }
  Result<bool> refresh() override {
    return guardedCall([&] { return m_inner->refresh(); },
                       [&](std::string_view detail) {
                         return failedOnException(fmt::format("{}: looking for new steps", file()),
                                                  detail);
                       });
  }
  Status setExtraArrays(const source::ExtraArrays& extras) override {
    return guardedCall([&] { return m_inner->setExtraArrays(extras); },
                       [&](std::string_view detail) {
                         return failedOnException(
                             fmt::format("{}: reading the extra arrays", file()), detail);
                       });
  }
  Result<source::SourceStep> read(int step) override {
    return guardedCall([&] { return m_inner->read(step); },
                       [&](std::string_view detail) {
                         return failedOnException(fmt::format("{}: reading step {}", file(), step),
                                                  detail);
                       });
  }

 private:
  std::unique_ptr<source::StepSource> m_inner;
};

// Whether two descriptions need different extractors.
bool sameExtraction(const pipeline::PipelineDescription& a,
                    const pipeline::PipelineDescription& b) {
  return a.file == b.file && a.cracks.method == b.cracks.method &&
         extractOptions(a) == extractOptions(b);
}

}  // namespace

// A plain move would replace the graph while the extractor that views it is
// still alive; the extractor goes first.
void ScenePipeline::restore(State&& state) {
  m_state.extractor.reset();
  m_state.graph.reset();
  m_state = std::move(state);
}

namespace {

// Whether the crack layer is coloured or thresholded by component rank.
bool usesComponents(const pipeline::CracksDescription& c) {
  using pipeline::CrackColourBy;
  return c.colourBy == CrackColourBy::kComponent ||
         (c.threshold && c.threshold->by == CrackColourBy::kComponent);
}

// The description's component filter, and the "component" cell array when
// cracks are coloured by component (largest first: 0 is the main crack).
void selectComponents(const pipeline::CracksDescription& c,
                      const cracks::CrackComponents& components, cracks::CrackMesh& mesh) {
  const cracks::ComponentFilter filter{c.minComponent, c.largest};
  const bool colour = usesComponents(c);
  if (!filter.active() && !colour) {
    return;
  }
  if (colour) {
    cracks::AttributeArray label{"component", cracks::AttributeType::kInt32, 1, {}};
    label.values.assign(mesh.primitiveCount(), -1.0);
    const std::size_t base = cracks::componentPrimitiveBase(mesh);
    for (std::size_t k = 0; k < components.ofPrimitive.size(); ++k) {
      label.values[base + k] = components.ofPrimitive[k];
    }
    mesh.cellData.push_back(std::move(label));
  }
  cracks::keepComponents(mesh, components, filter);
}

// Whether the crack layer is coloured or thresholded by opening or slip.
bool usesOpening(const pipeline::CracksDescription& c) {
  using pipeline::CrackColourBy;
  const auto opening = [](CrackColourBy by) {
    return by == CrackColourBy::kOpening || by == CrackColourBy::kSlip;
  };
  return opening(c.colourBy) || (c.threshold && opening(c.threshold->by));
}

// The "opening" and "slip" cell arrays, measured from the first step (the
// reference) before a component filter drops primitives, with the normals
// kept across steps (made on first use): a step costs its new breaks.
void addOpening(const pipeline::CracksDescription& c, const cracks::StepInput& step,
                std::span<const dem::Bond> bonds, const cracks::CrackComponents& components,
                std::shared_ptr<analysis::BondNormals>& normals, cracks::CrackMesh& mesh) {
  if (!usesOpening(c)) {
    return;
  }
  if (normals == nullptr) {
    normals = std::make_shared<analysis::BondNormals>(mesh.dimension);
  }
  normals->update(bonds, step.bondState, step.referencePositions);
  analysis::appendOpeningArrays(
      mesh, analysis::measureOpening(mesh, components, bonds, step.referencePositions,
                                     step.positions, {}, normals.get()));
}

// Whether two descriptions select or colour crack components differently.
bool sameSelection(const pipeline::CracksDescription& a, const pipeline::CracksDescription& b) {
  using pipeline::CrackColourBy;
  return a.largest == b.largest && a.minComponent == b.minComponent &&
         usesComponents(a) == usesComponents(b) && usesOpening(a) == usesOpening(b);
}

}  // namespace

cracks::ExtractOptions extractOptions(const pipeline::PipelineDescription& d) {
  cracks::ExtractOptions options;
  options.validate = d.cracks.validation;
  options.validationTolerance = d.cracks.validationTolerance;
  options.mergeOctahedra = d.cracks.mergeOctahedra;
  options.decomposition = d.cracks.decomposition;
  options.includeIntactFaces = d.showDecomposition;
  return options;
}

source::ExtraArrays extraArraysFor(const pipeline::PipelineDescription& d) {
  using pipeline::BondColourBy;
  using pipeline::CrackColourBy;
  using pipeline::ParticleColourBy;
  // What a layer colours by, and what its threshold selects by.
  const auto particlesUse = [&](ParticleColourBy by) {
    return d.particles.colourBy == by || (d.particles.threshold && d.particles.threshold->by == by);
  };
  const auto cracksUse = [&](CrackColourBy by) {
    return d.cracks.colourBy == by || (d.cracks.threshold && d.cracks.threshold->by == by);
  };
  const auto bondsUse = [&](BondColourBy by) {
    return d.bonds.colourBy == by || (d.bonds.threshold && d.bonds.threshold->by == by);
  };
  source::ExtraArrays extras;
  extras.velocities = particlesUse(ParticleColourBy::kVelocity);
  // One extra array per layer (the description's conversion checks): the
  // one coloured by, else the one thresholded by.
  if (d.particles.colourBy == ParticleColourBy::kExtra) {
    extras.particleExtra = d.particles.colourByExtra;
  } else if (particlesUse(ParticleColourBy::kExtra)) {
    extras.particleExtra = d.particles.threshold->byExtra;
  }
  if (d.bonds.colourBy == BondColourBy::kExtra) {
    extras.bondExtra = d.bonds.colourByExtra;
  } else if (bondsUse(BondColourBy::kExtra)) {
    extras.bondExtra = d.bonds.threshold->byExtra;
  }
  extras.bondForce = cracksUse(CrackColourBy::kForce) || bondsUse(BondColourBy::kForce);
  extras.breakStep = cracksUse(CrackColourBy::kBreakStep) || bondsUse(BondColourBy::kBreakStep);
  return extras;
}

std::string seriesKey(const pipeline::PipelineDescription& d) {
  using pipeline::RangeMode;
  std::string key;
  if (d.particles.visible && d.particles.range.mode == RangeMode::kSeries) {
    key +=
        fmt::format("p{}:{};", static_cast<int>(d.particles.colourBy), d.particles.colourByExtra);
  }
  if (d.cracks.visible && d.cracks.range.mode == RangeMode::kSeries) {
    key += fmt::format("c{};", static_cast<int>(d.cracks.colourBy));
  }
  if (d.bonds.show != pipeline::BondSelection::kNone && d.bonds.range.mode == RangeMode::kSeries) {
    key += fmt::format("b{}:{}:{};", static_cast<int>(d.bonds.colourBy), d.bonds.colourByExtra,
                       static_cast<int>(d.bonds.show));
  }
  return key;
}

ScenePipeline::ScenePipeline(SourceOpener opener, std::size_t cacheSteps)
    : m_opener(std::move(opener)), m_cacheSteps(cacheSteps) {}

ScenePipeline::~ScenePipeline() = default;

Result<std::unique_ptr<ScenePipeline>> ScenePipeline::open(
    pipeline::PipelineDescription description, SourceOpener opener, std::size_t cacheSteps) {
  std::unique_ptr<ScenePipeline> scene(new ScenePipeline(std::move(opener), cacheSteps));
  CRACKVIS_RETURN_IF_ERROR(scene->replace(std::move(description)));
  scene->commit();
  return scene;
}

Status ScenePipeline::replace(pipeline::PipelineDescription next) {
  commit();
  State before = m_state;
  Status status;
  try {
    status = apply(std::move(next));
  } catch (...) {
    restore(std::move(before));  // a throwing source or extractor changes nothing either
    throw;
  }
  if (!status) {
    restore(std::move(before));
    return status;
  }
  m_before = std::move(before);
  return Status::ok();
}

void ScenePipeline::revert() {
  if (m_before) {
    restore(std::move(*m_before));
    m_before.reset();
  }
}

void ScenePipeline::commit() {
  m_before.reset();
}

Status ScenePipeline::apply(pipeline::PipelineDescription next) {
  // What this change costs, and nothing of an earlier one: a change that
  // reads and extracts nothing reports zeros.
  m_timings = {};
  const bool empty = m_state.cache == nullptr;
  const bool newFile = empty || next.file != m_state.description.file;
  // Colouring by another array reads the file anew with it (rare: a menu
  // choice), so that the step cache never mixes steps with and without it.
  const bool reopen = newFile || extraArraysFor(next) != extraArraysFor(m_state.description);
  const bool newExtractor = reopen || !sameExtraction(next, m_state.description);
  const bool newSelection = !sameSelection(next.cracks, m_state.description.cracks);
  const bool stepChanged = next.step != m_state.description.step;
  const int shown = m_state.current ? m_state.current->index : -1;
  const auto targetIn = [&](int stepCount) {
    return newFile || stepChanged ? resolveStep(next.step, stepCount) : shown;
  };
  double openMs = 0.0;
  if (reopen) {
    const auto start = std::chrono::steady_clock::now();
    CRACKVIS_RETURN_IF_ERROR(openFile(next, targetIn));
    openMs = millisecondsSince(start);
  }
  const int target = targetIn(stepCount());
  CRACKVIS_RETURN_IF_ERROR(source::checkStepInRange(next.file, target, stepCount()));
  if (newExtractor) {
    m_state.normals.reset();  // another file or other bonds: found anew
    cracks::ExtractOptions options = extractOptions(next);
    options.decomposition =
        cracks::settledByFile(options.decomposition, source().recordedDecomposition());
    m_state.extractor = cracks::makeExtractor(next.cracks.method, *m_state.graph,
                                              source().lattice().dimension, options);
  }
  m_state.description = std::move(next);
  const std::string series = seriesKey(m_state.description);
  if (reopen || series != m_state.seriesKey) {
    CRACKVIS_RETURN_IF_ERROR(scanSeries());
  }
  if (reopen || target != shown) {
    CRACKVIS_RETURN_IF_ERROR(showStep(target));
    m_timings.openMs = openMs;
    m_timings.describeMs = reopen ? source().describeMs() : 0.0;
    return Status::ok();
  }
  if (newExtractor || newSelection) {
    m_timings = {};
    return extract(m_state.current);
  }
  return Status::ok();
}

namespace {

void widen(std::optional<ValueRange>& range, double v) {
  if (!std::isfinite(v)) {
    return;
  }
  if (!range) {
    range = ValueRange{v, v};
  }
  range->min = std::min(range->min, v);
  range->max = std::max(range->max, v);
}

// A crack face's value of a bond quantity, from its bond (what the
// extractor maps onto the faces); nullopt for component ranks and cell
// attribute's per-cell counts and loads, which need the extraction itself.
std::optional<double> crackFaceValue(const pipeline::CracksDescription& c, std::size_t b,
                                     const cracks::StepInput& step) {
  if (c.method == cracks::Method::kCellAttribute &&
      (c.colourBy == pipeline::CrackColourBy::kState ||
       c.colourBy == pipeline::CrackColourBy::kForce)) {
    return std::nullopt;
  }
  switch (c.colourBy) {
    case pipeline::CrackColourBy::kBondId:
      return static_cast<double>(b);
    case pipeline::CrackColourBy::kForce:
      return b < step.bondForce.size() ? std::optional<double>(step.bondForce[b]) : std::nullopt;
    case pipeline::CrackColourBy::kBreakStep:
      return b < step.breakStep.size() ? std::optional<double>(step.breakStep[b]) : std::nullopt;
    case pipeline::CrackColourBy::kState:
      return 1.0;
    case pipeline::CrackColourBy::kComponent:
    case pipeline::CrackColourBy::kOpening:
    case pipeline::CrackColourBy::kSlip:
    case pipeline::CrackColourBy::kSolid:
      break;
  }
  return std::nullopt;
}

}  // namespace

// Crack components, openings and slips would need every step extracted;
// they keep the step's range (docs/pipeline.md).
Status ScenePipeline::scanSeries() {
  const pipeline::PipelineDescription& d = m_state.description;
  m_state.series = {};
  m_state.seriesKey = seriesKey(d);
  if (m_state.seriesKey.empty()) {
    return Status::ok();
  }
  using pipeline::RangeMode;
  const bool particles = d.particles.visible && d.particles.range.mode == RangeMode::kSeries &&
                         d.particles.colourBy != pipeline::ParticleColourBy::kSolid;
  const bool cracks = d.cracks.visible && d.cracks.range.mode == RangeMode::kSeries;
  const bool bonds =
      d.bonds.show != pipeline::BondSelection::kNone && d.bonds.range.mode == RangeMode::kSeries;
  SeriesRanges ranges;
  for (int k = 0; k < stepCount(); ++k) {
    auto step = m_state.cache->readAside(k);
    if (!step) {
      return step.status();
    }
    SceneInput input;
    input.lattice = &source().lattice();
    input.step = stepInput(*step);
    input.initialPositions = m_state.initial->positions;
    input.velocities = step->velocities;
    input.particleExtra = step->particleExtra;
    input.bondExtra = step->bondExtra;
    if (particles) {
      for (double v : particleValues(d.particles, input)) {
        widen(ranges.particles, v);
      }
    }
    if (cracks) {
      for (std::size_t b = 0; b < step->bondState.size(); ++b) {
        if (step->bondState[b] != 0) {
          if (auto v = crackFaceValue(d.cracks, b, input.step)) {
            widen(ranges.cracks, *v);
          }
        }
      }
    }
    if (bonds) {
      for (double v : bondLines(d.bonds, input).values) {
        widen(ranges.bonds, v);
      }
    }
  }
  m_state.series = ranges;
  return Status::ok();
}

ScenePipeline::CrackMapping ScenePipeline::mappingOf(const cracks::CrackMesh& mesh,
                                                     const cracks::StepInput& input) const {
  const cracks::BondMapping mapping =
      cracks::mapBrokenBonds(mesh, input.bondState, *m_state.extractor);
  CrackMapping result{mapping.fraction(), {}};
  const std::string cause = cracks::diagnoseMapping(mapping, *m_state.extractor, *m_state.graph,
                                                    source().lattice().dimension, input.radius,
                                                    extractOptions(m_state.description));
  if (!cause.empty()) {
    result.warning = fmt::format("only {:.1f} % of the {} broken bonds became surface elements: {}",
                                 100.0 * mapping.fraction(), mapping.broken, cause);
    // "auto" followed the file's record; its advice to choose auto would
    // change nothing, so the warning names where the decomposition came from.
    const dem::CellDecomposition recorded = source().recordedDecomposition();
    if (m_state.description.cracks.decomposition == cracks::Decomposition::kAuto &&
        recorded != dem::CellDecomposition::kUnknown) {
      result.warning += fmt::format(
          " (auto took '{}' from the file's /index@decomposition; choose the decomposition to "
          "override it)",
          dem::decompositionName(recorded));
    }
  }
  return result;
}

Status ScenePipeline::openFile(const pipeline::PipelineDescription& d,
                               const std::function<int(int)>& stepShownIn) {
  auto opened = m_opener(d.file);
  if (!opened) {
    return opened.status();
  }
  auto guarded = std::make_unique<GuardedSource>(std::move(opened).value());
  if (guarded->stepCount() < 1) {
    return failedPrecondition(fmt::format("{}: the file has no steps", d.file));
  }
  CRACKVIS_RETURN_IF_ERROR(guarded->setExtraArrays(extraArraysFor(d)));
  auto cache = std::make_shared<source::StepCache>(std::move(guarded), m_cacheSteps);
  // Three things at once: the step to show is read on the cache's prefetch
  // thread (the show waits for it rather than reading it again), the first
  // step on this one, and the bond graph is built on a third (0.05-0.2 s at
  // 1e6 particles, 0.4-3 s at 1e7 on the 2-core development machine, where
  // fresh memory costs most of it).
  cache->prefetch(stepShownIn(cache->source().stepCount()));
  const dem::Lattice& lattice = cache->source().lattice();
  std::future<std::shared_ptr<const cracks::BondGraph>> built =
      std::async(std::launch::async, [&lattice] {
        return std::make_shared<const cracks::BondGraph>(lattice.particleCount(), lattice.bonds);
      });
  auto first = cache->get(0);
  auto graph = built.get();  // joined (and what it threw rethrown) before any return
  if (!first) {
    return first.status();
  }
  m_state.extractor.reset();  // views the graph replaced next
  m_state.current.reset();
  m_state.graph = std::move(graph);
  m_state.cache = std::move(cache);
  m_state.initial = first->step;
  return Status::ok();
}

Status ScenePipeline::showStep(int step) {
  CRACKVIS_RETURN_IF_ERROR(source::checkStepInRange(m_state.description.file, step, stepCount()));
  auto loaded = m_state.cache->get(step);
  if (!loaded) {
    return loaded.status();
  }
  m_timings = {};
  m_timings.loadMs = loaded->loadMs;
  return extract(loaded->step);
}

Status ScenePipeline::extract(std::shared_ptr<const source::SourceStep> step) {
  const auto start = std::chrono::steady_clock::now();
  const cracks::StepInput input = stepInput(*step);
  CRACKVIS_RETURN_IF_ERROR(m_state.extractor->extract(input, m_scratch));
  m_state.mapping = mappingOf(m_scratch, input);
  // The components, found once for the opening and the component colours
  // and filter (cell data added in between leaves them valid).
  const pipeline::CracksDescription& c = m_state.description.cracks;
  const bool needed = usesOpening(c) || usesComponents(c) ||
                      cracks::ComponentFilter{c.minComponent, c.largest}.active();
  const cracks::CrackComponents components =
      needed ? cracks::findComponents(m_scratch) : cracks::CrackComponents{};
  addOpening(c, input, source().lattice().bonds, components, m_state.normals, m_scratch);
  selectComponents(c, components, m_scratch);
  m_timings.extractMs = millisecondsSince(start);
  std::swap(m_scratch, m_state.mesh);
  m_state.current = std::move(step);
  return Status::ok();
}

void ScenePipeline::prefetch(int step) {
  m_state.cache->prefetch(step);
}

void ScenePipeline::setViewSize(int width, int height) {
  m_state.description.view.width = width;
  m_state.description.view.height = height;
}

Result<bool> ScenePipeline::refreshSteps() {
  return m_state.cache->refresh();
}

int ScenePipeline::stepCount() const {
  return m_state.cache->source().stepCount();
}

int ScenePipeline::step() const {
  return m_state.current->index;
}

const source::StepSource& ScenePipeline::source() const {
  return m_state.cache->source();
}

cracks::StepInput ScenePipeline::stepInput(const source::SourceStep& step) const {
  return {step.positions,
          step.bondState,
          source().lattice().radius,
          step.bondForce,
          source().breakSteps(),
          m_state.initial->positions,
          {},
          {}};
}

SceneInput ScenePipeline::input() const {
  return {&source().lattice(),
          stepInput(*m_state.current),
          m_state.initial->positions,
          m_state.current->velocities,
          &m_state.mesh,
          m_state.extractor->decomposition(),
          m_state.current->particleExtra,
          m_state.current->bondExtra,
          m_state.series,
          m_state.current->index,
          stepCount(),
          m_state.current->time,
          source().timeInIterations()};
}

}  // namespace crackvis::scene
