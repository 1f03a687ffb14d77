// The data half of a scene, GL-free: a pipeline description's file opened as
// a step source (with a step cache), its cracks extracted by the described
// method (incrementally across steps), and the result as a SceneInput for a
// renderer. One pipeline for every picture the project makes: the render
// server's sessions, `crackvis snapshot`, `crackvis-render --snapshot` and
// `crackvis movie`, so they cannot drift apart.
//
// Changes are all or nothing: a replacement or a step change that fails
// part-way (a file that opens but lacks the step, a read or an extraction
// that fails) leaves the pipeline showing what it showed. Not thread-safe:
// one owner thread (a session's).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/scene_model/scene_input.hpp>
#include <crackvis/source/step_source.hpp>

namespace crackvis::analysis {
class BondNormals;
}  // namespace crackvis::analysis

namespace crackvis::scene {

// Opens the step source of a description's file: the render server's goes
// through crackvis-data with the caller's folder rules, the CLI's reads a
// local file.
using SourceOpener =
    std::function<Result<std::unique_ptr<source::StepSource>>(const std::string& file)>;

// The extraction a description asks for (docs/pipeline.md).
cracks::ExtractOptions extractOptions(const pipeline::PipelineDescription& description);
// The arrays beyond positions and bond states that a description colours by:
// a pipeline reads them only then.
source::ExtraArrays extraArraysFor(const pipeline::PipelineDescription& description);

// The quantities whose ranges over the whole series a description asks for
// (range="series"), as text: a change of it means a new scan.
std::string seriesKey(const pipeline::PipelineDescription& description);

// What the last step change cost.
struct StepTimings {
  double openMs = 0.0;  // opening the file (its summary, lattice, first step); 0 when it was open
  double describeMs = 0.0;  // of openMs: the file's summary (crackvis-data's Describe)
  double loadMs = 0.0;      // 0 for a cached step
  double extractMs = 0.0;
};

class ScenePipeline {
 public:
  // A pipeline showing `description`'s step (negative: the last): NOT_FOUND
  // for an unknown file, FAILED_PRECONDITION for a file without steps,
  // OUT_OF_RANGE for a step outside the file, or the source's or the
  // extractor's error.
  static Result<std::unique_ptr<ScenePipeline>> open(pipeline::PipelineDescription description,
                                                     SourceOpener opener,
                                                     std::size_t cacheSteps = 8);
  ScenePipeline(const ScenePipeline&) = delete;
  ScenePipeline& operator=(const ScenePipeline&) = delete;
  ~ScenePipeline();

  // Shows `next`: reopens the file when it or the arrays to read change, makes
  // a new extractor when the extraction changes, shows `next`'s step when it
  // or the file changed (else the step shown) and extracts it when needed.
  // On failure nothing changed. The state before is kept until commit() or
  // the next replace, so that a caller whose own part of the change failed
  // (building the scene) can revert().
  Status replace(pipeline::PipelineDescription next);
  void revert();
  void commit();

  // Shows step `step` of the file (load and extract); on failure the step
  // shown stays.
  Status showStep(int step);
  // Reads `step` in the background (playing), unless cached or out of range.
  void prefetch(int step);

  const pipeline::PipelineDescription& description() const { return m_state.description; }
  // The view size the description records (a resized session's).
  void setViewSize(int width, int height);
  int stepCount() const;
  // Looks for new steps of a live file (StepSource::refresh): true when
  // there are more now. Showing one extracts cracks incrementally from the
  // step shown, as any step change does.
  Result<bool> refreshSteps();
  int step() const;  // the step shown
  const source::StepSource& source() const;
  const source::StepCache& cache() const { return *m_state.cache; }
  const cracks::CrackMesh& cracks() const { return m_state.mesh; }
  const StepTimings& timings() const { return m_timings; }
  // The series ranges of the layers that ask for them (empty otherwise).
  const SeriesRanges& seriesRanges() const { return m_state.series; }
  // How many of the shown step's broken bonds became surface elements, and
  // when fewer than 95 % did, the warning naming the likely cause (empty
  // otherwise): what extract prints, for the client's status bar.
  struct CrackMapping {
    double fraction = 1.0;
    std::string warning;
  };
  const CrackMapping& crackMapping() const { return m_state.mapping; }
  // The step shown, for a renderer; views this pipeline's data, valid until
  // its next change.
  SceneInput input() const;

 private:
  // Everything a change may replace. Member order is destruction order in
  // reverse: an extractor goes before the graph it views, the graph before
  // the cache whose source holds the bonds. Objects are shared between the
  // state shown and the state kept for revert().
  struct State {
    pipeline::PipelineDescription description;
    std::shared_ptr<source::StepCache> cache;
    std::shared_ptr<const cracks::BondGraph> graph;
    std::shared_ptr<cracks::CrackExtractor> extractor;
    std::shared_ptr<const source::SourceStep> initial;  // step 0: displacements
    std::shared_ptr<const source::SourceStep> current;
    // The crack's normals at its broken bonds, for colours by opening or
    // slip: kept across steps (only new breaks cost), like the extractor.
    std::shared_ptr<analysis::BondNormals> normals;
    cracks::CrackMesh mesh;
    CrackMapping mapping;
    SeriesRanges series;
    std::string seriesKey;  // of the description the ranges were scanned for
  };

  ScenePipeline(SourceOpener opener, std::size_t cacheSteps);
  Status apply(pipeline::PipelineDescription next);
  void restore(State&& state);
  // Opens the description's file; `stepShownIn(stepCount)` names the step
  // that will be shown, read ahead while the rest of the file is prepared.
  Status openFile(const pipeline::PipelineDescription& description,
                  const std::function<int(int)>& stepShownIn);
  Status extract(std::shared_ptr<const source::SourceStep> step);
  // Reads every step once (aside from the cache) for the series ranges.
  Status scanSeries();
  CrackMapping mappingOf(const cracks::CrackMesh& mesh, const cracks::StepInput& input) const;
  cracks::StepInput stepInput(const source::SourceStep& step) const;

  SourceOpener m_opener;
  std::size_t m_cacheSteps;
  State m_state;
  std::optional<State> m_before;
  cracks::CrackMesh m_scratch;  // the next mesh, swapped in on success
  StepTimings m_timings;
};

}  // namespace crackvis::scene
