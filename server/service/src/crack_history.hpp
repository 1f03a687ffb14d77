// StepHistory's crack numbers (its request's `cracks`): a method run over
// the steps of a file read through crackvis-data, in order, with the
// analyses of `crackvis report` and `crackvis info --steps --cracks`, added
// to the response's scalars. A user's run on a live file is kept between
// calls and continues from the last step it analysed. Private to the
// service library.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "crackvis/v1/render.pb.h"
#include <crackvis/analysis/growth.hpp>
#include <crackvis/common/status.hpp>
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/source/step_source.hpp>
#include <crackvis/vocabulary/crack_method.hpp>

namespace crackvis::service {

// A method and the analyses over a file's steps, in order, from step 0.
class CrackHistoryRun {
 public:
  // `recordedModes`: whether the file has the modes its code recorded
  // (dem::kBreakModeArray), which then count instead of the rule's.
  static Result<std::unique_ptr<CrackHistoryRun>> start(std::unique_ptr<source::StepSource> source,
                                                        cracks::Method method, bool recordedModes);
  CrackHistoryRun(const CrackHistoryRun&) = delete;
  CrackHistoryRun& operator=(const CrackHistoryRun&) = delete;

  // Whether a request for `file` with `method` continues this run.
  bool continues(const std::string& file, cracks::Method method, bool recordedModes) const;
  // Looks at a live file again, analyses its steps not analysed yet, up to
  // the `steps` the response's history counts, and adds the series of all
  // of them; `crack_steps_computed` says how many were new. `deadline`: the
  // caller's; DEADLINE_EXCEEDED, naming the step reached, once it passes
  // between two steps (the steps analysed until then stay analysed).
  Status addSeries(int steps, std::chrono::system_clock::time_point deadline,
                   v1::StepHistoryResponse& response);
  // A file its writer is still adding steps to: worth keeping.
  bool live() const { return m_source->appendable() && m_source->beingWritten(); }

 private:
  CrackHistoryRun(std::unique_ptr<source::StepSource> source, cracks::Method method,
                  bool recordedModes);
  Status analyseStep(int k);

  std::unique_ptr<source::StepSource> m_source;
  cracks::Method m_method;
  bool m_recordedModes;
  cracks::BondGraph m_graph;
  std::unique_ptr<cracks::CrackExtractor> m_extractor;
  analysis::CrackAnalysis m_analyses;
  std::vector<analysis::StepAnalysis> m_steps;
  std::vector<dem::Vec3> m_reference;
  cracks::CrackMesh m_mesh;
  std::vector<double> m_modes;
};

// One crack history per user at a time: each runs a method over a whole file
// on a call thread, so one user's repeated requests must not take them all.
// Keeps each user's run on a live file (one per user, dropped after
// kIdleRun without a call), so that a client following a running
// simulation costs the new steps only, not the whole run at every refresh.
class CrackHistories {
 public:
  static constexpr std::chrono::minutes kIdleRun{10};

  // RESOURCE_EXHAUSTED while `user` has one running.
  Status enter(const std::string& user);
  void leave(const std::string& user);
  // The user's kept run when it continues `file` with `method`; else null
  // (and a kept run of another file is dropped).
  std::unique_ptr<CrackHistoryRun> take(const std::string& user, const std::string& file,
                                        cracks::Method method, bool recordedModes);
  void keep(const std::string& user, std::unique_ptr<CrackHistoryRun> run);
  // Drops the runs no call has used for kIdleRun (the server's reaper).
  void dropIdle();

 private:
  struct Kept {
    std::unique_ptr<CrackHistoryRun> run;
    std::chrono::steady_clock::time_point used;
  };
  std::mutex m_mutex;
  std::set<std::string> m_running;
  std::map<std::string, Kept> m_kept;
};

}  // namespace crackvis::service
