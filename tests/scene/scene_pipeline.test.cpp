// The scene pipeline without GL: a description's file through a step source,
// its cracks extracted as the cracks library extracts them, changes all or
// nothing, and the extraction options compared as a whole.
#include <filesystem>

#include <catch2/catch.hpp>

#include "support/forwarding_source.hpp"
#include "support/h5_tamper.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/scene/scene_pipeline.hpp>
#include <crackvis/scene_model/scene_content.hpp>

namespace crackvis {
namespace {

// A series of 3 steps in which bonds break progressively, in a temp folder.
struct Series {
  testing::TempDir dir;
  std::string file = dir.file("run.h5");
  Series() { testing::writeSampleFile(file, 3, 3); }
};

scene::SourceOpener localOpener(const testing::TempDir& dir) {
  return [&dir](const std::string& file) { return source::openLocalSource(dir.file(file)); };
}

pipeline::PipelineDescription cellCut(std::int64_t step) {
  pipeline::PipelineDescription d;
  d.file = "run.h5";
  d.step = step;
  d.cracks.method = cracks::Method::kCellCut;
  return d;
}

// What the cracks library extracts from `path`'s step directly.
cracks::CrackMesh extractedDirectly(const std::string& path, const pipeline::PipelineDescription& d,
                                    int step) {
  auto series = cracks::DemSeries::open(path);
  REQUIRE(series);
  auto extractor = cracks::makeExtractor(d.cracks.method, (*series)->graph(),
                                         (*series)->lattice().dimension, scene::extractOptions(d));
  cracks::CrackMesh mesh;
  for (int k = 0; k <= step; ++k) {
    auto input = (*series)->load(k);
    REQUIRE(input);
    REQUIRE(extractor->extract(*input, mesh));
  }
  return mesh;
}

void requireSameGeometry(const cracks::CrackMesh& a, const cracks::CrackMesh& b) {
  REQUIRE(a.primitiveCount() > 0);
  CHECK(a.points == b.points);
  CHECK(a.polygons.connectivity == b.polygons.connectivity);
  CHECK(a.polygons.offsets == b.polygons.offsets);
  CHECK(a.lines.connectivity == b.lines.connectivity);
  CHECK(a.volumeCells.connectivity == b.volumeCells.connectivity);
}

}  // namespace

TEST_CASE("ExtractOptions compare every option, the domain included", "[scene][cracks]") {
  cracks::ExtractOptions a;
  cracks::ExtractOptions b;
  CHECK(a == b);
  b.domain = cracks::Box{{0, 0, 0}, {1, 1, 1}};
  CHECK(a != b);
  a.domain = cracks::Box{{0, 0, 0}, {1, 1, 1}};
  CHECK(a == b);
  a.domain->hi.z = 2.0;
  CHECK(a != b);
  b = a;
  b.minBrokenBonds = 3;
  CHECK(a != b);
}

TEST_CASE("a scene pipeline shows the description's step as the cracks library extracts it",
          "[scene]") {
  const Series series;
  for (const cracks::Method method :
       {cracks::Method::kCellCut, cracks::Method::kLocalVoronoi, cracks::Method::kCellAttribute}) {
    DYNAMIC_SECTION(cracks::toString(method)) {
      auto d = cellCut(-1);
      d.cracks.method = method;
      auto scene = scene::ScenePipeline::open(d, localOpener(series.dir));
      REQUIRE(scene);
      CHECK((*scene)->stepCount() == 3);
      CHECK((*scene)->step() == 2);  // -1: the last
      requireSameGeometry((*scene)->cracks(), extractedDirectly(series.file, d, 2));
      const scene::SceneInput input = (*scene)->input();
      REQUIRE(input.lattice != nullptr);
      CHECK(input.step.positions.size() == input.lattice->particleCount());
      CHECK(input.initialPositions.size() == input.lattice->particleCount());
      CHECK(input.step.positions.data() != input.initialPositions.data());
      CHECK(input.cracks == &(*scene)->cracks());
      // The cell methods keep a decomposition, drawn as edges on request.
      CHECK((input.decomposition != nullptr) == (method != cracks::Method::kLocalVoronoi));
    }
  }
}

TEST_CASE("auto takes the cell decomposition the file records instead of deciding it again",
          "[scene][cracks]") {
  // The sample is a lattice. A copy that records "triangulation" gets the
  // triangulation's cracks under auto, which deciding on its bonds would not.
  const Series series;
  const std::string recorded = series.dir.file("recorded.h5");
  std::filesystem::copy_file(series.file, recorded);
  testing::setStringAttribute(recorded, dem::kSpatialIndexGroup, "decomposition", "triangulation");
  auto d = cellCut(-1);
  d.cracks.method = cracks::Method::kCellCentre;  // its points are the cells' centres
  REQUIRE(d.cracks.decomposition == cracks::Decomposition::kAuto);
  auto lattice = d;
  lattice.cracks.decomposition = cracks::Decomposition::kLattice;
  auto triangulation = d;
  triangulation.cracks.decomposition = cracks::Decomposition::kTriangulation;
  const cracks::CrackMesh asLattice = extractedDirectly(series.file, lattice, 2);
  const cracks::CrackMesh asTriangulation = extractedDirectly(series.file, triangulation, 2);
  REQUIRE(asLattice.points != asTriangulation.points);

  auto plain = scene::ScenePipeline::open(d, localOpener(series.dir));
  REQUIRE(plain);
  CHECK((*plain)->source().recordedDecomposition() != dem::CellDecomposition::kTriangulation);
  requireSameGeometry((*plain)->cracks(), asLattice);

  d.file = "recorded.h5";
  auto settled = scene::ScenePipeline::open(d, localOpener(series.dir));
  REQUIRE(settled);
  CHECK((*settled)->source().recordedDecomposition() == dem::CellDecomposition::kTriangulation);
  requireSameGeometry((*settled)->cracks(), asTriangulation);
  // A chosen decomposition is the view's, whatever the file records.
  d.cracks.decomposition = cracks::Decomposition::kLattice;
  REQUIRE((*settled)->replace(d));
  requireSameGeometry((*settled)->cracks(), asLattice);
}

TEST_CASE("a wrong recorded decomposition gives poorer cracks and a warning that names it",
          "[scene][cracks]") {
  // A random packing whose file claims a lattice: auto follows the claim, as
  // choosing "lattice" would, and the warning says where it came from.
  testing::TempDir dir;
  testing::writePlantedRandomPacking(dir.file("claims-lattice.h5"), 2);
  testing::setStringAttribute(dir.file("claims-lattice.h5"), dem::kSpatialIndexGroup,
                              "decomposition", "lattice");
  auto d = cellCut(-1);
  d.file = "claims-lattice.h5";
  auto scene = scene::ScenePipeline::open(d, localOpener(dir));
  REQUIRE(scene);
  CHECK((*scene)->crackMapping().fraction < 0.95);
  CHECK_THAT((*scene)->crackMapping().warning, Catch::Contains("span no lattice"));
  CHECK_THAT((*scene)->crackMapping().warning,
             Catch::Contains("auto took 'lattice' from the file's /index@decomposition"));
  // Chosen, the triangulation maps them, whatever the file claims.
  d.cracks.decomposition = cracks::Decomposition::kTriangulation;
  REQUIRE((*scene)->replace(d));
  CHECK((*scene)->crackMapping().fraction >= 0.95);
  CHECK((*scene)->crackMapping().warning.empty());
}

TEST_CASE("a failed scene change leaves the pipeline as it was", "[scene]") {
  const Series series;
  auto opened = scene::ScenePipeline::open(cellCut(1), localOpener(series.dir));
  REQUIRE(opened);
  scene::ScenePipeline& scene = **opened;
  const cracks::CrackMesh shown = scene.cracks();
  REQUIRE(shown.primitiveCount() > 0);
  auto unchanged = [&] {
    CHECK(scene.step() == 1);
    CHECK(scene.description() == cellCut(1));
    CHECK(scene.cracks().points == shown.points);
    CHECK(scene.cracks().polygons.connectivity == shown.polygons.connectivity);
  };

  SECTION("a step outside the file") {
    auto next = cellCut(7);
    next.cracks.method = cracks::Method::kLocalVoronoi;
    const Status status = scene.replace(next);
    CHECK(status.code() == StatusCode::kOutOfRange);
    CHECK_THAT(status.message(), Catch::Contains("step 7 out of range (the file has steps 0..2)"));
    unchanged();
  }
  SECTION("a file that does not exist") {
    auto next = cellCut(0);
    next.file = "missing.h5";
    const Status status = scene.replace(next);
    CHECK(status.code() == StatusCode::kNotFound);
    CHECK_THAT(status.message(), Catch::Contains("missing.h5"));
    unchanged();
  }
  SECTION("a step change outside the file") {
    CHECK(scene.showStep(3).code() == StatusCode::kOutOfRange);
    CHECK(scene.showStep(-2).code() == StatusCode::kOutOfRange);
    unchanged();
  }
  SECTION("a change that succeeded and is reverted") {
    auto next = cellCut(2);
    next.cracks.method = cracks::Method::kLocalVoronoi;
    REQUIRE(scene.replace(next));
    CHECK(scene.step() == 2);
    CHECK(scene.description() == next);
    requireSameGeometry(scene.cracks(), extractedDirectly(series.file, next, 2));
    scene.revert();
    unchanged();
    // Nothing is kept once committed: revert() then changes nothing.
    REQUIRE(scene.replace(next));
    scene.commit();
    scene.revert();
    CHECK(scene.description() == next);
  }
}

TEST_CASE("a scene pipeline extracts anew only when the extraction changes", "[scene]") {
  const Series series;
  auto opened = scene::ScenePipeline::open(cellCut(2), localOpener(series.dir));
  REQUIRE(opened);
  scene::ScenePipeline& scene = **opened;
  // The extractor's decomposition tells extractors apart (the state before a
  // replacement is kept until the next one, so addresses are not reused).
  auto decomposition = [&] { return scene.input().decomposition; };
  const auto* first = decomposition();
  REQUIRE(first != nullptr);

  // Another colour: the same extractor (its decomposition object) and step.
  auto coloured = cellCut(2);
  coloured.cracks.colour = {1, 2, 3};
  REQUIRE(scene.replace(coloured));
  CHECK(decomposition() == first);

  // Another extraction option: a new extractor, though file, step and method
  // stay.
  auto merged = coloured;
  merged.cracks.mergeOctahedra = true;
  REQUIRE(scene.replace(merged));
  CHECK(decomposition() != first);
  CHECK(scene.step() == 2);
}

// A local source that says its file took 12.5 ms to describe, as a remote
// one measures crackvis-data's Describe.
class DescribedSource final : public testing::ForwardingSource {
 public:
  using ForwardingSource::ForwardingSource;
  double describeMs() const override { return 12.5; }
};

TEST_CASE("a scene pipeline's timings are those of its last change alone", "[scene]") {
  const Series series;
  scene::SourceOpener opener =
      [&series](const std::string& file) -> Result<std::unique_ptr<source::StepSource>> {
    auto local = source::openLocalSource(series.dir.file(file));
    if (!local) {
      return local.status();
    }
    return std::unique_ptr<source::StepSource>(
        std::make_unique<DescribedSource>(std::move(local).value()));
  };
  auto opened = scene::ScenePipeline::open(cellCut(1), opener);
  REQUIRE(opened);
  scene::ScenePipeline& scene = **opened;
  // The open: the file, of which its Describe.
  CHECK(scene.timings().openMs > 0.0);
  CHECK(scene.timings().describeMs == 12.5);
  // Another step of the open file: no open, no Describe.
  REQUIRE(scene.replace(cellCut(2)));
  CHECK(scene.timings().openMs == 0.0);
  CHECK(scene.timings().describeMs == 0.0);
  // Another colour only: nothing read or extracted, and nothing of the
  // changes before reported again.
  auto coloured = cellCut(2);
  coloured.cracks.colour = {1, 2, 3};
  REQUIRE(scene.replace(coloured));
  CHECK(scene.timings().openMs == 0.0);
  CHECK(scene.timings().describeMs == 0.0);
  CHECK(scene.timings().loadMs == 0.0);
  CHECK(scene.timings().extractMs == 0.0);
}

// A random packing with a planted through crack and scattered breaks.
struct PlantedSeries {
  testing::TempDir dir;
  std::string file = dir.file("run.h5");
  PlantedSeries() { testing::writePlantedRandomPacking(file, 4, 0.02); }
};

// Local Voronoi at the planted series' last step.
std::unique_ptr<scene::ScenePipeline> openPlanted(const PlantedSeries& series,
                                                  pipeline::PipelineDescription& d) {
  d = cellCut(4);
  d.cracks.method = cracks::Method::kLocalVoronoi;
  auto opened = scene::ScenePipeline::open(d, localOpener(series.dir));
  REQUIRE(opened);
  return std::move(opened).value();
}

TEST_CASE("a scene pipeline shows the largest crack components and colours by component",
          "[scene][cracks]") {
  const PlantedSeries series;
  pipeline::PipelineDescription d;
  auto opened = openPlanted(series, d);
  scene::ScenePipeline& scene = *opened;
  const cracks::CrackComponents all = cracks::findComponents(*scene.input().cracks);
  REQUIRE(all.components.size() >= 2);  // the sample's breaks make several pieces

  // The same extractor, a new selection: the current step is shown anew.
  d.cracks.largest = 1;
  d.cracks.colourBy = pipeline::CrackColourBy::kComponent;
  REQUIRE(scene.replace(d));
  const cracks::CrackMesh& main = *scene.input().cracks;
  const cracks::CrackComponents kept = cracks::findComponents(main);
  REQUIRE(kept.components.size() == 1);
  CHECK(kept.components[0].area == Approx(all.components[0].area));
  const cracks::AttributeArray* label = main.findCellData("component");
  REQUIRE(label != nullptr);
  REQUIRE(label->values.size() == main.primitiveCount());
  for (std::size_t k = 0; k < main.polygons.size(); ++k) {
    CHECK(label->values[main.vertices.size() + main.lines.size() + k] == 0.0);
  }

  // A minimum area above every piece leaves no surface.
  d.cracks.largest = 0;
  d.cracks.minComponent = 2.0 * all.components[0].area;
  REQUIRE(scene.replace(d));
  CHECK(scene.input().cracks->polygons.size() == 0);
}

TEST_CASE("a scene pipeline selects and colours cell attribute's components too",
          "[scene][cracks]") {
  const PlantedSeries series;
  pipeline::PipelineDescription d;
  auto opened = openPlanted(series, d);
  d.cracks.method = cracks::Method::kCellAttribute;
  scene::ScenePipeline& scene = *opened;
  REQUIRE(scene.replace(d));
  const cracks::CrackComponents all = cracks::findComponents(*scene.input().cracks);
  REQUIRE(all.components.size() >= 2);
  CHECK(all.components[0].area > 0.0);

  d.cracks.largest = 1;
  d.cracks.colourBy = pipeline::CrackColourBy::kComponent;
  REQUIRE(scene.replace(d));
  const cracks::CrackMesh& main = *scene.input().cracks;
  REQUIRE(main.hasVolumeCells());
  CHECK(main.volumeCells.size() == all.components[0].primitives);
  CHECK(main.volumeCellTypes.size() == main.volumeCells.size());
  const cracks::AttributeArray* label = main.findCellData("component");
  REQUIRE(label != nullptr);
  REQUIRE(label->values.size() == main.primitiveCount());
  for (double value : label->values) {
    CHECK(value == 0.0);
  }
  const cracks::AttributeArray* broken = main.findCellData("broken_bonds");
  REQUIRE(broken != nullptr);
  CHECK(broken->values.size() == main.primitiveCount());
}

TEST_CASE("a scene pipeline says when few broken bonds became crack surfaces, and why",
          "[scene][cracks]") {
  const PlantedSeries series;
  pipeline::PipelineDescription d;
  auto opened = openPlanted(series, d);
  scene::ScenePipeline& scene = *opened;
  CHECK(scene.crackMapping().fraction >= 0.95);
  CHECK(scene.crackMapping().warning.empty());
  // The lattice's cells on a random packing: fragments, and a warning.
  d.cracks.decomposition = cracks::Decomposition::kLattice;
  REQUIRE(scene.replace(d));
  CHECK(scene.crackMapping().fraction < 0.95);
  CHECK_THAT(scene.crackMapping().warning,
             Catch::StartsWith("only ") && Catch::Contains("span no lattice"));
}

}  // namespace crackvis

namespace crackvis {

TEST_CASE("a series colour range spans every step and survives step changes", "[scene][legend]") {
  const Series series;
  auto d = cellCut(0);
  d.particles.colourBy = pipeline::ParticleColourBy::kDisplacement;
  d.particles.range.mode = pipeline::RangeMode::kSeries;
  d.cracks.colourBy = pipeline::CrackColourBy::kBreakStep;
  d.cracks.range.mode = pipeline::RangeMode::kSeries;
  auto scene = scene::ScenePipeline::open(d, localOpener(series.dir));
  REQUIRE(scene);
  // The largest displacement of any particle at any step, computed here
  // from the file directly.
  auto file = cracks::DemSeries::open(series.file);
  REQUIRE(file);
  auto first = (*file)->load(0);
  REQUIRE(first);
  const std::vector<dem::Vec3> initial(first->positions.begin(), first->positions.end());
  double largest = 0.0;
  int latestBreak = -1;
  for (int k = 0; k < 3; ++k) {
    auto step = (*file)->load(k);
    REQUIRE(step);
    for (std::size_t i = 0; i < initial.size(); ++i) {
      largest = std::max(largest, dem::norm(step->positions[i] - initial[i]));
    }
    for (std::size_t b = 0; b < step->bondState.size(); ++b) {
      if (step->bondState[b] != 0) {
        latestBreak = std::max(latestBreak, static_cast<int>(step->breakStep[b]));
      }
    }
  }
  REQUIRE(largest > 0.0);
  REQUIRE(latestBreak > 0);
  const auto& ranges = (*scene)->seriesRanges();
  REQUIRE(ranges.particles);
  CHECK(ranges.particles->min == 0.0);
  CHECK(ranges.particles->max == Approx(largest));
  REQUIRE(ranges.cracks);
  CHECK(ranges.cracks->max == latestBreak);
  CHECK_FALSE(ranges.bonds);
  // Step 0 shows fewer breaks than the series has: its own range is smaller.
  CHECK((*scene)->input().series.cracks == ranges.cracks);
  REQUIRE((*scene)->showStep(2));
  CHECK((*scene)->seriesRanges().cracks == ranges.cracks);
  // Back to per-step ranges: nothing scanned.
  d.particles.range.mode = pipeline::RangeMode::kStep;
  d.cracks.range.mode = pipeline::RangeMode::kStep;
  REQUIRE((*scene)->replace(d));
  CHECK_FALSE((*scene)->seriesRanges().particles);
  CHECK_FALSE((*scene)->seriesRanges().cracks);
}

TEST_CASE("cell attribute's cells carry the bond quantities crack colour-by names",
          "[scene][legend]") {
  const Series series;
  auto d = cellCut(2);
  d.cracks.method = cracks::Method::kCellAttribute;
  d.cracks.colourBy = pipeline::CrackColourBy::kBreakStep;
  auto scene = scene::ScenePipeline::open(d, localOpener(series.dir));
  REQUIRE(scene);
  const cracks::CrackMesh& mesh = (*scene)->cracks();
  REQUIRE(mesh.primitiveCount() > 0);
  for (pipeline::CrackColourBy by :
       {pipeline::CrackColourBy::kBreakStep, pipeline::CrackColourBy::kBondId,
        pipeline::CrackColourBy::kState}) {
    const cracks::AttributeArray* array =
        mesh.findCellData(scene::crackArrayName(by, cracks::Method::kCellAttribute));
    REQUIRE(array != nullptr);
    CHECK(array->values.size() == mesh.primitiveCount());
  }
  // Every cell shown has a broken bond, so a first break at a step of the file.
  for (double step : mesh.findCellData("break_step")->values) {
    CHECK(step >= 0.0);
    CHECK(step <= 2.0);
  }
  // bond_id stays the one-bond-per-face array of the other methods.
  CHECK(mesh.findCellData("bond_id") == nullptr);
}

}  // namespace crackvis

namespace crackvis {

TEST_CASE("a crack layer coloured by opening or slip carries them as cell data",
          "[scene][analysis]") {
  testing::TempDir dir;
  testing::writePlantedLattice(dir.file("run.h5"), 8);
  pipeline::PipelineDescription d;
  d.file = "run.h5";
  d.step = -1;
  d.cracks.method = cracks::Method::kLocalVoronoi;
  d.cracks.colourBy = pipeline::CrackColourBy::kOpening;
  auto scene = scene::ScenePipeline::open(d, localOpener(dir));
  REQUIRE(scene);
  const auto mean = [](const cracks::AttributeArray* array, double& largest) {
    REQUIRE(array != nullptr);
    double sum = 0.0;
    std::size_t counted = 0;
    largest = 0.0;
    for (double v : array->values) {
      if (!std::isnan(v)) {
        sum += v;
        largest = std::max(largest, v);
        ++counted;
      }
    }
    REQUIRE(counted > 0);
    return sum / static_cast<double>(counted);
  };
  double largest = 0.0;
  // The right half moved one bond length (2 mm) by the last step.
  CHECK(mean((*scene)->cracks().findCellData("opening"), largest) == Approx(2e-3).epsilon(0.02));
  CHECK(largest == Approx(2e-3).epsilon(0.01));
  CHECK(mean((*scene)->cracks().findCellData("slip"), largest) < 1e-4);
  CHECK(scene::crackArrayName(d.cracks.colourBy, d.cracks.method) == std::string("opening"));

  SECTION("back to solid colour: extracted again without them") {
    auto next = d;
    next.cracks.colourBy = pipeline::CrackColourBy::kSolid;
    REQUIRE((*scene)->replace(next));
    CHECK((*scene)->cracks().findCellData("opening") == nullptr);
  }
  SECTION("an earlier step opens less") {
    auto next = d;
    next.step = 4;
    REQUIRE((*scene)->replace(next));
    CHECK(mean((*scene)->cracks().findCellData("opening"), largest) == Approx(1e-3).epsilon(0.02));
  }
}

TEST_CASE("particles coloured by fragment: the halves of a through crack", "[scene][analysis]") {
  testing::TempDir dir;
  const auto sample = testing::writePlantedLattice(dir.file("run.h5"), 8);
  pipeline::PipelineDescription d;
  d.file = "run.h5";
  d.step = -1;
  d.particles.colourBy = pipeline::ParticleColourBy::kFragment;
  auto scene = scene::ScenePipeline::open(d, localOpener(dir));
  REQUIRE(scene);
  const std::vector<double> labels = scene::particleValues(d.particles, (*scene)->input());
  REQUIRE(labels.size() == sample.lattice.particleCount());
  CHECK(*std::max_element(labels.begin(), labels.end()) == 1.0);
  // Every particle left of the cut is in one fragment, every one right of it
  // in the other.
  const auto& last = sample.steps.back().positions;
  const auto& first = sample.steps.front().positions;
  double leftLabel = -1.0;
  double rightLabel = -1.0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    double& label = last[i].x > first[i].x + 1e-9 ? rightLabel : leftLabel;
    if (label < 0.0) {
      label = labels[i];
    }
    CHECK(labels[i] == label);
  }
  CHECK(leftLabel != rightLabel);
  // Intact at step 0: one fragment.
  auto intact = d;
  intact.step = 0;
  REQUIRE((*scene)->replace(intact));
  const std::vector<double> whole = scene::particleValues(d.particles, (*scene)->input());
  CHECK(*std::max_element(whole.begin(), whole.end()) == 0.0);
}

}  // namespace crackvis
