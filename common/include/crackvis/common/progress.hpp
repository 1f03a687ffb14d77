// A terminal progress bar for long CLI work (simulation, extraction, export).
//
// Draws on stderr with carriage returns when stderr is a terminal, and prints
// a plain line every ~10 % otherwise, so CI logs stay readable. Not
// thread-safe: update it from the thread that drives the work.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

namespace crackvis {

class ProgressBar {
 public:
  ProgressBar(std::string label, std::int64_t total, std::FILE* out = stderr);
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  ~ProgressBar();

  // Sets the amount done so far and an optional detail shown after the bar
  // ("t=0.012 s, broken 1204").
  void update(std::int64_t done, const std::string& detail = {});
  // Draws the final state and ends the line; called by the destructor too.
  void finish();

  // False silences the bar entirely (for --quiet and for tests).
  void setEnabled(bool enabled) { m_enabled = enabled; }

 private:
  void draw(const std::string& detail, bool final);

  std::string m_label;
  std::int64_t m_total;
  std::int64_t m_done = 0;
  std::FILE* m_out;
  bool m_isTerminal;
  bool m_enabled = true;
  bool m_finished = false;
  int m_lastDecile = -1;
  std::chrono::steady_clock::time_point m_start;
  std::chrono::steady_clock::time_point m_lastDraw;
  std::string m_lastDetail;
};

}  // namespace crackvis
