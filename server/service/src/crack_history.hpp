// StepHistory's crack numbers (its request's `cracks`): a method run over
// the steps of a file read through crackvis-data, in order, with the
// analyses of `crackvis report` and `crackvis info --steps --cracks`, added
// to the response's scalars. A user's run on a live file is kept between
// calls and continues from the last step it analysed. Private to the
// service library.
#pragma once

#include <chrono>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
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
  // The series of every step analysed, and how many of them were new.
  struct Series {
    std::vector<analysis::NamedSeries> series;
    int computed = 0;
  };
  // Looks at a live file again, analyses its steps not analysed yet, up to
  // the `steps` the response's history counts, and gives the series of all
  // of them. `deadline`: the caller's; DEADLINE_EXCEEDED, naming the step
  // reached, once it passes between two steps (the steps analysed until
  // then stay analysed).
  Result<Series> series(int steps, std::chrono::system_clock::time_point deadline);
  // A file its writer is still adding steps to: worth keeping.
  bool live() const { return m_source->appendable() && m_source->beingWritten(); }
  // Every step of a file no writer adds to any more has been analysed.
  bool finished() const {
    return !live() && static_cast<int>(m_steps.size()) == m_source->stepCount();
  }

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

// The series of finished files, by file revision (DescribeResponse.revision,
// which names the file's bytes), method and whether recorded modes counted:
// every StepHistory call on a finished file would otherwise run the method
// over all its steps again (seconds on a 200-step file, for each user who
// opens the Steps plot). The revision names one file on disk whatever its
// name in a user's folders, so users who may read it share its entry. Least
// recently used entries go first past kMaxBytes.
class FinishedSeries {
 public:
  static constexpr std::size_t kMaxBytes = std::size_t{32} << 20;

  static std::string key(const std::string& revision, cracks::Method method, bool recordedModes,
                         int steps);
  std::optional<std::vector<analysis::NamedSeries>> find(const std::string& key);
  void store(const std::string& key, std::vector<analysis::NamedSeries> series);
  std::size_t entries() const;

 private:
  struct Entry {
    std::string key;
    std::vector<analysis::NamedSeries> series;
    std::size_t bytes = 0;
  };
  void evictTo(std::size_t bytes);

  mutable std::mutex m_mutex;
  std::list<Entry> m_recent;
  std::unordered_map<std::string, std::list<Entry>::iterator> m_byKey;
  std::size_t m_bytes = 0;
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
