#include "report_writer.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>

#include <crackvis/common/pending_file.hpp>

extern char** environ;

namespace crackvis::cli {
namespace {

namespace fs = std::filesystem;

// A number for a CSV cell: "nan" where there is none (gnuplot skips it).
std::string cell(double v) {
  return std::isfinite(v) ? fmt::format("{:.9g}", v) : std::string("nan");
}

// A step scalar's name in a file name or a gnuplot string: letters,
// digits, '_', '.', '-' kept, anything else '_'.
std::string safeName(const std::string& name) {
  std::string out = name;
  for (char& c : out) {
    const bool kept =
        std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '-';
    c = kept ? c : '_';
  }
  return out;
}

// The tables. Column numbers in the scripts below follow these headers.
// step, time, broken_bonds, then the crack's numbers (analysis::crackSeries,
// the names the clients' Steps plot shows too), then the file's step scalars.
std::string growthTable(const ReportData& d) {
  std::vector<analysis::StepAnalysis> steps;
  for (const ReportRow& row : d.rows) {
    steps.push_back(row.step);
  }
  const std::vector<analysis::NamedSeries> series = analysis::crackSeries(steps, d.front);
  std::string out = "step,time,broken_bonds";
  for (const analysis::NamedSeries& s : series) {
    out += ',' + s.name;
  }
  for (const std::string& name : d.scalarNames) {
    out += ',' + name;
  }
  out += "\n";
  for (std::size_t k = 0; k < d.rows.size(); ++k) {
    const analysis::StepAnalysis& s = d.rows[k].step;
    out += fmt::format("{},{},{}", s.step, cell(s.time), s.broken);
    for (const analysis::NamedSeries& column : series) {
      out += ',' + cell(column.values[k]);
    }
    for (double v : d.rows[k].scalars) {
      out += ',' + cell(v);
    }
    out += "\n";
  }
  return out;
}
constexpr int kGrowthFixedColumns = 15;

std::string componentTable(const ReportData& d) {
  std::string out = "component,elements,area,mean_opening,max_opening,mean_slip,max_slip\n";
  const auto row = [&](const std::string& name, const analysis::OpeningSummary& s) {
    out += fmt::format("{},{},{},{},{},{},{}\n", name, s.elements, cell(s.area),
                       cell(s.meanOpening), cell(s.maxOpening), cell(s.meanSlip), cell(s.maxSlip));
  };
  row("all", analysis::summariseOpening(d.at.openings, -1));
  for (std::size_t c = 0; c < d.at.components.size(); ++c) {
    row(std::to_string(c), d.at.components[c]);
  }
  return out;
}

// The histogram's range: from 0 (or the least opening, when a crack
// closed) to the largest opening.
std::pair<double, double> openingRange(const analysis::ElementOpenings& o) {
  double lo = 0.0;
  double hi = 0.0;
  for (double v : o.opening) {
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  return {lo, hi > lo ? hi : lo + 1e-12};
}

std::string histogramTable(const ReportData& d) {
  const auto [lo, hi] = openingRange(d.at.openings);
  // The top edge inclusive: stretch the range by a hair.
  const double top = hi + 1e-9 * (hi - lo);
  const analysis::Histogram main = analysis::openingHistogram(d.at.openings, 0, lo, top, d.bins);
  const analysis::Histogram all = analysis::openingHistogram(d.at.openings, -1, lo, top, d.bins);
  std::string out = "bin_lo,bin_hi,main_area,all_area\n";
  for (std::size_t k = 0; k < main.weight.size(); ++k) {
    const double from = lo + main.binWidth() * static_cast<double>(k);
    out += fmt::format("{},{},{},{}\n", cell(from), cell(from + main.binWidth()),
                       cell(main.weight[k]), cell(all.weight[k]));
  }
  return out;
}

dem::Vec3 profileAxis(const ReportData& d) {
  if (d.rows.empty() || d.at.openings.size() == 0) {
    return {};
  }
  const auto at = std::find_if(d.rows.begin(), d.rows.end(),
                               [&](const ReportRow& r) { return r.step.step == d.at.step; });
  const dem::Vec3 normal = at != d.rows.end() ? at->step.mainNormal : dem::Vec3{};
  return analysis::longestAxis(d.at.openings, 0, normal);
}

std::string profileTable(const ReportData& d) {
  std::string out = "position,area,opening,slip\n";
  for (const analysis::ProfileBin& bin :
       analysis::openingProfile(d.at.openings, 0, profileAxis(d), d.bins)) {
    out += fmt::format("{},{},{},{}\n", cell(bin.position), cell(bin.area), cell(bin.opening),
                       cell(bin.slip));
  }
  return out;
}

std::vector<analysis::Fragment> keptFragments(const ReportData& d) {
  std::vector<analysis::Fragment> kept;
  for (const analysis::Fragment& f : d.at.fragments.fragments) {
    if (f.particles >= d.minFragment) {
      kept.push_back(f);
    }
  }
  return kept;
}

std::string fragmentTable(const ReportData& d) {
  std::string out = "rank,particles,volume,volume_share\n";
  const std::vector<analysis::Fragment> kept = keptFragments(d);
  for (std::size_t r = 0; r < kept.size(); ++r) {
    const double share =
        d.at.fragments.totalVolume > 0.0 ? kept[r].volume / d.at.fragments.totalVolume : 0.0;
    out += fmt::format("{},{},{},{}\n", r, kept[r].particles, cell(kept[r].volume), cell(share));
  }
  return out;
}

// Cumulative distribution of fragment volume, smallest first: the share of
// fragments, and of their volume, at or below each volume.
std::string fragmentCdfTable(const ReportData& d) {
  std::vector<analysis::Fragment> kept = keptFragments(d);
  std::reverse(kept.begin(), kept.end());
  double total = 0.0;
  for (const analysis::Fragment& f : kept) {
    total += f.volume;
  }
  std::string out = "volume,fraction_of_fragments,fraction_of_volume\n";
  double below = 0.0;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    below += kept[k].volume;
    out += fmt::format("{},{},{}\n", cell(kept[k].volume),
                       cell(static_cast<double>(k + 1) / static_cast<double>(kept.size())),
                       cell(total > 0.0 ? below / total : 0.0));
  }
  return out;
}

std::string orientationTable(const ReportData& d) {
  const int size = std::max(d.bins, 4);
  if (d.dimension == 2) {
    const analysis::RoseDiagram main = analysis::roseDiagram(d.at.openings, 0, 2 * size);
    const analysis::RoseDiagram all = analysis::roseDiagram(d.at.openings, -1, 2 * size);
    std::string out = "angle_lo,angle_hi,main_length,all_length\n";
    for (std::size_t k = 0; k < main.weight.size(); ++k) {
      const double from = main.binDegrees() * static_cast<double>(k);
      out += fmt::format("{},{},{},{}\n", cell(from), cell(from + main.binDegrees()),
                         cell(main.weight[k]), cell(all.weight[k]));
    }
    return out;
  }
  const analysis::Stereonet main = analysis::stereonet(d.at.openings, 0, 2 * size);
  const analysis::Stereonet all = analysis::stereonet(d.at.openings, -1, 2 * size);
  std::string out = "x,y,main_area,all_area\n";
  for (int row = 0; row < main.size; ++row) {
    for (int column = 0; column < main.size; ++column) {
      const auto k = static_cast<std::size_t>(row * main.size + column);
      out += fmt::format("{},{},{},{}\n", cell(main.cellCentre(column)), cell(main.cellCentre(row)),
                         cell(main.weight[k]), cell(all.weight[k]));
    }
  }
  return out;
}

// mode: the one counted (the code's record where it has one, else the
// rule's); rule_mode: the rule's; source: which of the two `mode` is.
std::string breakTable(const ReportData& d) {
  std::string out = "bond,step,mode,rule_mode,source,stretch,shear\n";
  for (const analysis::BondBreak& b : d.breaks) {
    out += fmt::format("{},{},{},{},{},{},{}\n", b.bond, b.step, analysis::toString(b.mode),
                       analysis::toString(b.rule), b.recorded ? "recorded" : "rule",
                       cell(b.stretch), cell(b.shear));
  }
  return out;
}

// "27 of 27 bonds have the code's own mode; the rule agrees on 27 of them".
std::string recordedModes(const ReportData& d) {
  std::size_t recorded = 0;
  std::size_t agree = 0;
  for (const analysis::BondBreak& b : d.breaks) {
    recorded += b.recorded ? 1 : 0;
    agree += b.recorded && b.rule == b.mode ? 1 : 0;
  }
  if (recorded == 0) {
    return "No break mode was recorded by the code: every mode is the rule's.";
  }
  return fmt::format(
      "{} of the {} breaks have the mode the code recorded (the file's bonds/break_mode, from "
      "`crackvis import`), and those are counted; crackvis's own rule agrees on {} of them "
      "({:.1f} %).",
      recorded, d.breaks.size(), agree,
      100.0 * static_cast<double>(agree) / static_cast<double>(recorded));
}

// gnuplot scripts: each draws NAME.png (through NAME.png.partial) from the
// tables in the same folder, so a user can edit and rerun it there.
std::string scriptHead(const std::string& name, int width, int height) {
  return fmt::format(
      "# {0}.png from the tables beside it: gnuplot {0}.gp\n"
      "set terminal pngcairo size {1},{2} font \"sans,10\"\n"
      "set output '{0}.png.partial'\n"
      "set datafile separator comma\n"
      "set datafile missing 'nan'\n"
      "set grid\n",
      name, width, height);
}

std::string growthScript(const ReportData& d) {
  const char* area = d.dimension == 2 ? "length [m]" : "area [m^2]";
  return scriptHead("growth", 1200, 900) +
         fmt::format(
             "set multiplot layout 2,2 title 'Crack growth: {0}'\n"
             "set xlabel 'step'\n"
             "set ylabel 'crack {1}'\n"
             "plot 'growth.csv' skip 1 using 1:4 with lines lw 2 title 'all cracks', \\\n"
             "     '' skip 1 using 1:6 with lines lw 2 title 'main crack'\n"
             "set ylabel 'main crack front extent along {2} [m]'\n"
             "plot 'growth.csv' skip 1 using 1:7 with lines lw 2 notitle\n"
             "set ylabel 'fragments'\n"
             "set y2label 'largest fragment share'\n"
             "set y2range [0:1.05]\n"
             "set ytics nomirror\n"
             "set y2tics\n"
             "plot 'growth.csv' skip 1 using 1:12 with steps lw 2 title 'fragments', \\\n"
             "     '' skip 1 using 1:13 axes x1y2 with lines lw 2 title 'largest share'\n"
             "unset y2tics\n"
             "unset y2label\n"
             "set ytics mirror\n"
             "set ylabel 'broken bonds'\n"
             "plot 'growth.csv' skip 1 using 1:14 with lines lw 2 title 'tension', \\\n"
             "     '' skip 1 using 1:15 with lines lw 2 title 'shear'\n"
             "unset multiplot\n",
             fs::path(d.file).filename().string(), area, analysis::axisName(d.front.axis));
}

// Crack area against one step scalar (load, displacement...).
std::string scalarScript(const ReportData& d, std::size_t s) {
  const std::string name = safeName(d.scalarNames[s]);
  const int column = kGrowthFixedColumns + 1 + static_cast<int>(s);
  return scriptHead("growth-vs-" + name, 900, 600) +
         fmt::format(
             "set title 'Crack {1} against {0}'\n"
             "set xlabel '{0}'\n"
             "set ylabel 'crack {1}'\n"
             "plot 'growth.csv' skip 1 using {2}:4 with linespoints pt 7 ps 0.5 title 'all "
             "cracks', \\\n"
             "     '' skip 1 using {2}:6 with linespoints pt 7 ps 0.5 title 'main crack'\n",
             name, d.dimension == 2 ? "length [m]" : "area [m^2]", column);
}

std::string openingScript(const ReportData& d) {
  return scriptHead("opening", 1200, 500) +
         fmt::format(
             "set multiplot layout 1,2 title 'Crack opening at step {0}'\n"
             "set style fill solid 0.6\n"
             "set xlabel 'opening [m]'\n"
             "set ylabel '{1}'\n"
             "plot 'opening_histogram.csv' skip 1 using (($1+$2)/2):4:($2-$1) with boxes "
             "title 'all cracks', \\\n"
             "     '' skip 1 using (($1+$2)/2):3:($2-$1) with boxes title 'main crack'\n"
             "set xlabel 'position along the main crack [m]'\n"
             "set ylabel 'mean [m]'\n"
             "plot 'opening_profile.csv' skip 1 using 1:3 with linespoints pt 7 lw 2 title "
             "'opening', \\\n"
             "     '' skip 1 using 1:4 with linespoints pt 7 lw 2 title 'slip'\n"
             "unset multiplot\n",
             d.at.step, d.dimension == 2 ? "crack length [m]" : "crack area [m^2]");
}

std::string fragmentScript(const ReportData& d) {
  return scriptHead("fragments", 900, 600) +
         fmt::format(
             "set title 'Fragment sizes at step {0} (at least {1} particle{2})'\n"
             "set logscale x\n"
             "set xlabel 'fragment volume [{3}]'\n"
             "set ylabel 'cumulative fraction'\n"
             "set yrange [0:1.05]\n"
             "set key left top\n"
             "plot 'fragments_cdf.csv' skip 1 using 1:2 with steps lw 2 title 'of fragments', \\\n"
             "     '' skip 1 using 1:3 with steps lw 2 title 'of volume'\n",
             d.at.step, d.minFragment, d.minFragment == 1 ? "" : "s",
             d.dimension == 2 ? "m^2" : "m^3");
}

std::string orientationScript(const ReportData& d) {
  if (d.dimension == 2) {
    return scriptHead("orientation", 700, 700) +
           fmt::format(
               "set title 'Crack normals at step {0} (rose, by length)'\n"
               "set polar\n"
               "set angles degrees\n"
               "set size square\n"
               "unset border\n"
               "set grid polar 30\n"
               "unset xtics\n"
               "unset ytics\n"
               "set style fill transparent solid 0.4\n"
               "plot 'orientation.csv' skip 1 using (($1+$2)/2):4 with impulses lw 6 title "
               "'all cracks', \\\n"
               "     '' skip 1 using (($1+$2)/2+180):4 with impulses lw 6 notitle, \\\n"
               "     '' skip 1 using (($1+$2)/2):3 with impulses lw 3 title 'main crack', \\\n"
               "     '' skip 1 using (($1+$2)/2+180):3 with impulses lw 3 notitle\n",
               d.at.step);
  }
  return scriptHead("orientation", 1200, 560) +
         fmt::format(
             "set multiplot layout 1,2 title 'Crack normals at step {0}: lower-hemisphere "
             "equal-area net, by area'\n"
             "set size ratio -1\n"
             "set xrange [-1.05:1.05]\n"
             "set yrange [-1.05:1.05]\n"
             "unset grid\n"
             "set palette defined (0 'white', 1 '#fde725', 2 '#21918c', 3 '#440154')\n"
             "set object 1 circle at 0,0 size 1 front fillstyle empty border lc 'black'\n"
             "set title 'all cracks'\n"
             "plot 'orientation.csv' skip 1 using 1:2:4 with image notitle\n"
             "set title 'main crack'\n"
             "plot 'orientation.csv' skip 1 using 1:2:3 with image notitle\n"
             "unset multiplot\n",
             d.at.step);
}

// Runs gnuplot on NAME.gp in `folder` and moves NAME.png into place;
// its messages go to gnuplot.log there.
Status drawPlot(const fs::path& folder, const std::string& name) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, (folder / "gnuplot.log").c_str(),
                                   O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addchdir_np(&actions, folder.c_str());
  const std::string script = name + ".gp";
  char program[] = "gnuplot";
  std::vector<char*> argv{program, const_cast<char*>(script.c_str()), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, program, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    return failedPrecondition(
        spawned == ENOENT ? std::string("gnuplot is not installed (Debian: apt-get install "
                                        "gnuplot-nox); the tables and the .gp scripts are written")
                          : fmt::format("cannot run gnuplot: {}", std::strerror(spawned)));
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const fs::path partial = folder / (name + ".png.partial");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    return internalError(fmt::format("gnuplot failed on {} (see {})", (folder / script).string(),
                                     (folder / "gnuplot.log").string()));
  }
  std::error_code error;
  fs::rename(partial, folder / (name + ".png"), error);
  if (error) {
    return failedPrecondition(
        fmt::format("{}: cannot write ({})", (folder / (name + ".png")).string(), error.message()));
  }
  return Status::ok();
}

std::string vec(dem::Vec3 v) {
  return fmt::format("({:.3f}, {:.3f}, {:.3f})", v.x, v.y, v.z);
}

std::string summaryLines(const ReportData& d) {
  const auto at = std::find_if(d.rows.begin(), d.rows.end(),
                               [&](const ReportRow& r) { return r.step.step == d.at.step; });
  if (at == d.rows.end()) {
    return {};
  }
  const analysis::StepAnalysis& s = at->step;
  const char* unit = d.dimension == 2 ? "m" : "m²";
  const analysis::MeanOrientation mean = analysis::meanOrientation(d.at.openings, 0);
  std::string out = fmt::format(
      "| quantity at step {} | value |\n|---|---|\n"
      "| broken bonds | {} |\n"
      "| crack {} (all components) | {:.6g} {} |\n"
      "| components | {} |\n"
      "| main crack {} | {:.6g} {} |\n",
      s.step, s.broken, d.dimension == 2 ? "length" : "area", s.totalArea, unit, s.components,
      d.dimension == 2 ? "length" : "area", s.mainArea, unit);
  if (s.mainOpening.elements > 0) {
    out += fmt::format(
        "| main crack opening: mean, max | {:.6g} m, {:.6g} m |\n"
        "| main crack slip: mean, max | {:.6g} m, {:.6g} m |\n",
        s.mainOpening.meanOpening, s.mainOpening.maxOpening, s.mainOpening.meanSlip,
        s.mainOpening.maxSlip);
  } else {
    out += "| opening | none: the method's elements carry no bonds (cell attribute) |\n";
  }
  out += fmt::format(
      "| fragments of at least {} particle{} | {} |\n"
      "| largest fragment's share of the volume | {:.4f} |\n"
      "| main crack's mean normal, strength | {} , {:.3f} |\n"
      "| bonds broken in tension, in shear (steps seen) | {}, {} |\n",
      d.minFragment, d.minFragment == 1 ? "" : "s", s.fragments, s.largestFragmentShare,
      vec(mean.normal), mean.strength, s.tension, s.shear);
  return out;
}

std::string indexPage(const ReportData& d, const ReportFiles& files) {
  const auto plotted = [&](const std::string& png) {
    return std::find(files.plots.begin(), files.plots.end(), png) != files.plots.end()
               ? fmt::format("![{0}]({0})\n\n", png)
               : std::string();
  };
  std::string page = fmt::format(
      "# Crack report: {}\n\n"
      "Method: **{}**; steps {} to {} ({} steps read); tables at step {}.\n\n"
      "Command: `{}`\n\n",
      fs::path(d.file).filename().string(), d.method, d.rows.empty() ? 0 : d.rows.front().step.step,
      d.rows.empty() ? 0 : d.rows.back().step.step, d.rows.size(), d.at.step, d.options);
  page += summaryLines(d) + "\n";
  if (!files.plotProblem.empty()) {
    page += fmt::format("Plots are missing: {}.\n\n", files.plotProblem);
  }
  for (const std::string& reason : files.notDrawn) {
    page += fmt::format("Not drawn: {}.\n\n", reason);
  }
  page += "## Crack growth\n\n" + plotted("growth.png");
  for (const std::string& name : d.scalarNames) {
    page += plotted("growth-vs-" + safeName(name) + ".png");
  }
  page += fmt::format(
      "Table: [growth.csv](growth.csv), one row per step (the front is the main crack's extent "
      "along {}).\n\n",
      analysis::axisName(d.front.axis));
  page += "## Crack opening\n\n" + plotted("opening.png") +
          "Tables: [opening_components.csv](opening_components.csv) (per component), "
          "[opening_histogram.csv](opening_histogram.csv) (area-weighted), "
          "[opening_profile.csv](opening_profile.csv) (along the main crack's longest "
          "in-plane axis " +
          vec(profileAxis(d)) + ").\n\n";
  page += "## Fragments\n\n" + plotted("fragments.png") +
          "Tables: [fragments.csv](fragments.csv), [fragments_cdf.csv](fragments_cdf.csv).\n\n";
  page += "## Orientation and break modes\n\n" + plotted("orientation.png") +
          "Tables: [orientation.csv](orientation.csv), [break_modes.csv](break_modes.csv) (each "
          "bond the first step it is seen broken). " +
          recordedModes(d) + "\n\n";
  page +=
      "## How these are measured\n\n"
      "- Opening and slip: each surface element's bond, its ends' separation now minus in the "
      "reference (the first step), split along the crack's local normal (the plane through the "
      "element centroids nearby).\n"
      "- Fragments: connected pieces of the intact bonds; volume from the radii.\n"
      "- Orientation: the crack's local normals, weighted by area (2D: length).\n"
      "- Break mode: the code's own record where the file has one (bonds/break_mode); else "
      "tension when the bond's stretch (|d| - |d0|) exceeds 0.05 times its sideways jump and "
      "its last force seen was not compressive, shear otherwise.\n\n"
      "The rules in full: docs/methods.md, \"From pictures to numbers\".\n";
  return page;
}

}  // namespace

Result<ReportFiles> writeReport(const ReportData& data, const std::string& folder, bool plots) {
  const fs::path dir(folder);
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) {
    return failedPrecondition(
        fmt::format("{}: cannot create folder ({})", folder, error.message()));
  }
  ReportFiles files;
  const std::pair<const char*, std::string> tables[] = {
      {"growth.csv", growthTable(data)},
      {"opening_components.csv", componentTable(data)},
      {"opening_histogram.csv", histogramTable(data)},
      {"opening_profile.csv", profileTable(data)},
      {"fragments.csv", fragmentTable(data)},
      {"fragments_cdf.csv", fragmentCdfTable(data)},
      {"orientation.csv", orientationTable(data)},
      {"break_modes.csv", breakTable(data)},
  };
  for (const auto& [name, text] : tables) {
    CRACKVIS_RETURN_IF_ERROR(replaceFile((dir / name).string(), text));
    files.tables.push_back(name);
  }
  // A plot whose tables hold nothing (no opening: cell attribute's cells
  // carry no bond; no surface; every fragment dust) is not drawn: gnuplot
  // fails on a table without points. The page says why.
  const bool opened = analysis::summariseOpening(data.at.openings, -1).elements > 0;
  const bool surface = data.at.openings.size() > 0;
  const bool pieces = !keptFragments(data).empty();
  struct Script {
    std::string name;
    std::string text;
    const char* empty;  // why there is nothing to draw, or nullptr
  };
  std::vector<Script> scripts = {
      {"growth", growthScript(data), nullptr},
      {"opening", openingScript(data),
       opened ? nullptr : "no element carries a bond (cell attribute's cells), so no opening"},
      {"fragments", fragmentScript(data),
       pieces ? nullptr : "every fragment is smaller than --min-fragment"},
      {"orientation", orientationScript(data),
       surface ? nullptr : "the crack has no surface elements at that step"},
  };
  for (std::size_t s = 0; s < data.scalarNames.size(); ++s) {
    scripts.push_back(
        {"growth-vs-" + safeName(data.scalarNames[s]), scalarScript(data, s), nullptr});
  }
  for (const Script& script : scripts) {
    CRACKVIS_RETURN_IF_ERROR(replaceFile((dir / (script.name + ".gp")).string(), script.text));
  }
  if (!plots) {
    files.plotProblem = "not drawn (--no-plots); run gnuplot on the .gp scripts";
  } else {
    fs::remove(dir / "gnuplot.log", error);
    for (const Script& script : scripts) {
      if (script.empty != nullptr) {
        files.notDrawn.push_back(fmt::format("{}.png: {}", script.name, script.empty));
        continue;
      }
      if (Status drawn = drawPlot(dir, script.name); !drawn) {
        files.plotProblem = drawn.message();
        break;  // gnuplot missing or broken: the next ones would fail alike
      }
      files.plots.push_back(script.name + ".png");
    }
  }
  CRACKVIS_RETURN_IF_ERROR(replaceFile((dir / "index.md").string(), indexPage(data, files)));
  return files;
}

}  // namespace crackvis::cli
