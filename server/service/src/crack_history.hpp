// StepHistory's crack numbers (its request's `cracks`): a method run over
// every step of a file read through crackvis-data, in order, with the
// analyses of `crackvis report` and `crackvis info --steps --cracks`, added
// to the response's scalars. Private to the service library.
#pragma once

#include <chrono>
#include <mutex>
#include <set>
#include <string>

#include "crackvis/v1/render.pb.h"
#include <crackvis/common/status.hpp>
#include <crackvis/source/step_source.hpp>
#include <crackvis/vocabulary/crack_method.hpp>

namespace crackvis::service {

// `deadline`: the caller's; DEADLINE_EXCEEDED, naming the step reached, once
// it passes between two steps.
// `recordedModes`: whether the file has the modes its code recorded
// (dem::kBreakModeArray), which then count instead of the rule's.
Status addCrackSeries(source::StepSource& source, cracks::Method method, bool recordedModes,
                      std::chrono::system_clock::time_point deadline,
                      v1::StepHistoryResponse& response);

// One crack history per user at a time: each runs a method over a whole file
// on a call thread, so one user's repeated requests must not take them all.
class CrackHistoryGate {
 public:
  // RESOURCE_EXHAUSTED while `user` has one running.
  Status enter(const std::string& user);
  void leave(const std::string& user);

 private:
  std::mutex m_mutex;
  std::set<std::string> m_running;
};

}  // namespace crackvis::service
