// What `crackvis report` writes: the tables (CSV), the gnuplot scripts and
// their PNG plots, and the page (index.md) that links them with the method
// and the options used. Every file goes through PendingFile: a report that
// fails half way leaves the files of an earlier report whole.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <crackvis/analysis/growth.hpp>
#include <crackvis/common/status.hpp>

namespace crackvis::cli {

// One step's row: the analyses and the step scalars of the file (NaN where
// a step has none of a name).
struct ReportRow {
  analysis::StepAnalysis step;
  std::vector<double> scalars;  // in ReportData::scalarNames' order
};

// The step whose opening, fragments and orientation the per-step tables show.
struct ReportSnapshot {
  int step = -1;
  analysis::ElementOpenings openings;
  std::vector<analysis::OpeningSummary> components;  // largest first
  analysis::Fragments fragments;
};

struct ReportData {
  std::string file;
  std::string method;
  std::string options;  // the command line, for the page
  int dimension = 3;
  std::size_t minFragment = 1;
  int bins = 20;
  std::vector<std::string> scalarNames;
  std::vector<ReportRow> rows;
  analysis::CrackFront front;
  ReportSnapshot at;
  std::vector<analysis::BondBreak> breaks;
};

struct ReportFiles {
  std::vector<std::string> tables;
  std::vector<std::string> plots;     // PNGs drawn
  std::string plotProblem;            // why plots are missing, if they are
  std::vector<std::string> notDrawn;  // "NAME.png: why", plots with nothing to draw
};

// Writes the tables and the scripts, then runs gnuplot on each script
// (unless `plots` is false), then the page.
Result<ReportFiles> writeReport(const ReportData& data, const std::string& folder, bool plots);

}  // namespace crackvis::cli
