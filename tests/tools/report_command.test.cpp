// crackvis report on runs whose numbers are known: a planted crack (its
// opening, fragments and front), a 2D one, and Yade's JCFpm notched bar,
// whose crack file records the mode of every break.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using crackvis::testing::fileText;
using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {

const std::string kCli = CRACKVIS_CLI;

using Table = std::vector<std::map<std::string, std::string>>;

// A CSV file as rows keyed by the header's names.
Table readCsv(const std::string& path) {
  std::istringstream in(fileText(path));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream header(line);
  for (std::string name; std::getline(header, name, ',');) {
    names.push_back(name);
  }
  Table rows;
  while (std::getline(in, line)) {
    std::stringstream cells(line);
    std::map<std::string, std::string> row;
    std::size_t k = 0;
    for (std::string cell; std::getline(cells, cell, ','); ++k) {
      row[k < names.size() ? names[k] : std::to_string(k)] = cell;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

double number(const std::map<std::string, std::string>& row, const std::string& name) {
  const auto found = row.find(name);
  REQUIRE(found != row.end());
  return std::stod(found->second);
}

bool isPng(const std::string& path) {
  return fileText(path).rfind("\x89PNG", 0) == 0;
}

const char* const kTables[] = {
    "growth.csv",    "opening_components.csv", "opening_histogram.csv", "opening_profile.csv",
    "fragments.csv", "fragments_cdf.csv",      "orientation.csv",       "break_modes.csv"};

}  // namespace

TEST_CASE("crackvis report measures a planted crack's opening, fragments and growth",
          "[cli][report]") {
  TempDir dir;
  const std::string data = dir.file("planted.h5");
  // Radius 1 mm: bond length 2 mm, and the right half moves 2 mm by the end.
  REQUIRE(runProcess(
              {kCli, "generate", "--sites", "21", "11", "11", "--planted-crack", "20", "-o", data})
              .exitCode == 0);
  const std::string out = dir.file("report");
  const auto run = runProcess({kCli, "report", data, "-o", out, "-q"});
  REQUIRE(run.exitCode == 0);
  for (const char* table : kTables) {
    INFO(table);
    CHECK(std::filesystem::exists(out + "/" + table));
  }
  for (const char* plot : {"growth", "opening", "fragments", "orientation"}) {
    INFO(plot);
    CHECK(isPng(fmt::format("{}/{}.png", out, plot)));
    CHECK(std::filesystem::exists(fmt::format("{}/{}.gp", out, plot)));
  }
  const std::string page = fileText(out + "/index.md");
  for (const char* table : kTables) {
    CHECK_THAT(page, Catch::Contains(fmt::format("({})", table)));
  }
  CHECK_THAT(page, Catch::Contains("![growth.png](growth.png)"));
  CHECK_THAT(page, Catch::Contains("local-voronoi"));

  const Table growth = readCsv(out + "/growth.csv");
  REQUIRE(growth.size() == 21);
  CHECK(number(growth.front(), "fragments") == 1.0);
  CHECK(number(growth.back(), "fragments") == 2.0);
  CHECK(number(growth.back(), "main_mean_opening") == Approx(2e-3).epsilon(0.01));
  CHECK(number(growth.back(), "main_mean_slip") < 0.02 * 2e-3);
  // The front climbs to the top at 3/4 of the steps, then stays.
  CHECK(number(growth[5], "front_extent") < number(growth[10], "front_extent"));
  CHECK(number(growth[16], "front_extent") == Approx(number(growth.back(), "front_extent")));
  CHECK(number(growth.back(), "tension_breaks") + number(growth.back(), "shear_breaks") ==
        number(growth.back(), "broken_bonds"));

  const Table fragments = readCsv(out + "/fragments.csv");
  REQUIRE(fragments.size() == 2);  // the halves; lone particles are dust (--min-fragment 2)
  CHECK(number(fragments[0], "volume_share") + number(fragments[1], "volume_share") ==
        Approx(1.0).epsilon(0.01));
  const Table profile = readCsv(out + "/opening_profile.csv");
  REQUIRE(profile.size() >= 10);
  const Table orientation = readCsv(out + "/orientation.csv");
  CHECK(orientation.front().count("x") == 1);  // 3D: the equal-area net

  SECTION("crackvis info --steps --cracks shows the same numbers beside the step scalars") {
    const auto info =
        runProcess({kCli, "info", data, "--steps", "--cracks", "local-voronoi", "--json"});
    REQUIRE(info.exitCode == 0);
    const auto json = nlohmann::json::parse(info.out);
    const auto& last = json.at("per_step").back().at("cracks");
    CHECK(last.at("fragments").get<double>() == number(growth.back(), "fragments"));
    CHECK(last.at("main_area").get<double>() ==
          Approx(number(growth.back(), "main_area")).epsilon(1e-6));
    CHECK(last.at("front_axis") == "z");
    const auto refused = runProcess({kCli, "info", data, "--cracks", "local-voronoi"});
    CHECK(refused.exitCode == 2);
    CHECK_THAT(refused.err, Catch::Contains("--steps"));
    // And tools/plots/step_scalars.sh draws any of them against any other.
    const auto plot = runProcess({"/usr/bin/env", "CRACKS=local-voronoi", "CRACKVIS=" + kCli,
                                  std::string(CRACKVIS_SOURCE_DIR) + "/tools/plots/step_scalars.sh",
                                  data, "time", "main_area", dir.file("area.png")});
    INFO(plot.err);
    CHECK(plot.exitCode == 0);
    CHECK(isPng(dir.file("area.png")));
  }
  SECTION("--at picks the step of the per-step tables, and refuses one not read") {
    const std::string early = dir.file("early");
    REQUIRE(
        runProcess({kCli, "report", data, "-o", early, "-q", "--at", "5", "--no-plots"}).exitCode ==
        0);
    CHECK_THAT(fileText(early + "/index.md"), Catch::Contains("tables at step 5"));
    CHECK_FALSE(std::filesystem::exists(early + "/growth.png"));
    CHECK(std::filesystem::exists(early + "/growth.gp"));
    const auto refused =
        runProcess({kCli, "report", data, "-o", early, "-s", "0:10", "--at", "15", "-q"});
    CHECK(refused.exitCode == 2);
    CHECK_THAT(refused.err, Catch::Contains("--at 15"));
  }
  SECTION("without gnuplot the tables and scripts are written, with a warning") {
    const std::string bare = dir.file("bare");
    const auto noPlot = runProcess(
        {"/usr/bin/env", "PATH=" + dir.file("nowhere"), kCli, "report", data, "-o", bare, "-q"});
    CHECK(noPlot.exitCode == 0);
    CHECK_THAT(noPlot.err, Catch::Contains("gnuplot is not installed"));
    CHECK(std::filesystem::exists(bare + "/growth.csv"));
    CHECK_THAT(fileText(bare + "/index.md"), Catch::Contains("Plots are missing"));
  }
  SECTION("cell attribute's cells carry no bonds: no opening plot, the page says why") {
    const std::string cells = dir.file("cells");
    const auto run = runProcess({kCli, "report", data, "-o", cells, "-q", "-m", "cell-attribute"});
    CHECK(run.exitCode == 0);
    CHECK(run.err.empty());
    CHECK_FALSE(std::filesystem::exists(cells + "/opening.png"));
    CHECK(isPng(cells + "/growth.png"));
    CHECK_THAT(fileText(cells + "/index.md"), Catch::Contains("Not drawn: opening.png"));
    CHECK(readCsv(cells + "/opening_profile.csv").empty());
  }
  SECTION("bad input: a missing file, an output that is a file") {
    const auto missing = runProcess({kCli, "report", dir.file("none.h5"), "-o", out, "-q"});
    CHECK(missing.exitCode == 1);
    CHECK_THAT(missing.err, Catch::StartsWith("crackvis report:"));
    std::ofstream(dir.file("taken")) << "a file";
    const auto taken = runProcess({kCli, "report", data, "-o", dir.file("taken"), "-q"});
    CHECK(taken.exitCode == 1);
    CHECK(fileText(dir.file("taken")) == "a file");
  }
}

TEST_CASE("crackvis report on a 2D run draws a rose diagram", "[cli][report]") {
  TempDir dir;
  const std::string data = dir.file("flat.h5");
  REQUIRE(runProcess({kCli, "generate", "--lattice", "triangular", "--sites", "30", "40",
                      "--planted-crack", "8", "-o", data})
              .exitCode == 0);
  const std::string out = dir.file("report");
  REQUIRE(runProcess({kCli, "report", data, "-o", out, "-q"}).exitCode == 0);
  const Table orientation = readCsv(out + "/orientation.csv");
  REQUIRE(orientation.front().count("angle_lo") == 1);
  // The crack runs along y: its normals near 0 (or 180) degrees.
  double across = 0.0;
  double total = 0.0;
  for (const auto& row : orientation) {
    const double angle = number(row, "angle_lo");
    const double length = number(row, "main_length");
    total += length;
    across += angle < 10.0 || angle >= 170.0 ? length : 0.0;
  }
  CHECK(across > 0.95 * total);
  CHECK(isPng(out + "/orientation.png"));
  // The right half moved one bond length, 2 mm, by the last step.
  const Table growth = readCsv(out + "/growth.csv");
  CHECK(number(growth.back(), "main_mean_opening") == Approx(2e-3).epsilon(0.01));
}

TEST_CASE(
    "crackvis report on Yade's JCFpm notched bar agrees with JCFpm's crack file, bond for "
    "bond",
    "[cli][report][yade]") {
  TempDir dir;
  const std::string run = std::string(CRACKVIS_TEST_DATA) + "/yade/notched_bar";
  const std::string data = dir.file("yade.h5");
  REQUIRE(runProcess({kCli, "import", "yade", run, "-o", data, "-q"}).exitCode == 0);
  const std::string out = dir.file("report");
  REQUIRE(runProcess({kCli, "report", data, "-o", out, "-q"}).exitCode == 0);
  for (const char* table : kTables) {
    CHECK(std::filesystem::exists(out + "/" + table));
  }
  // The step scalars (JCFpm's counts among them) have their plots too.
  CHECK(isPng(out + "/growth-vs-jcfpm_cracks.png"));

  // JCFpm's records: iteration, contact point, type (1 tensile, 2 shear).
  struct Record {
    double iteration;
    crackvis::dem::Vec3 at;
    int type;
  };
  std::vector<Record> records;
  std::istringstream text(fileText(run + "/cracks_notched_bar.txt"));
  std::string line;
  std::getline(text, line);
  for (Record r; text >> r.iteration;) {
    double time = 0.0;
    text >> time >> r.at.x >> r.at.y >> r.at.z >> r.type;
    std::getline(text, line);
    records.push_back(r);
  }
  REQUIRE(records.size() == 27);

  auto reader = crackvis::dem::DemFileReader::open(data);
  REQUIRE(reader);
  const auto lattice = reader->readLattice();
  REQUIRE(lattice);
  const Table growth = readCsv(out + "/growth.csv");
  const Table breaks = readCsv(out + "/break_modes.csv");
  REQUIRE(breaks.size() == records.size());
  // Each break of ours, at the step it was first seen, against the JCFpm
  // records logged since the step before: the one nearest its bond's
  // midpoint, which must be within a radius and have the same mode.
  std::vector<char> used(records.size(), 0);
  for (const auto& row : breaks) {
    const int step = static_cast<int>(number(row, "step"));
    const double until = number(growth[static_cast<std::size_t>(step)], "source_step");
    const double since = number(growth[static_cast<std::size_t>(step - 1)], "source_step");
    const auto state = reader->readStep(step);
    REQUIRE(state);
    const auto bond = lattice->bonds[static_cast<std::size_t>(number(row, "bond"))];
    const crackvis::dem::Vec3 mid = 0.5 * (state->positions[static_cast<std::size_t>(bond.first)] +
                                           state->positions[static_cast<std::size_t>(bond.second)]);
    std::size_t best = records.size();
    double bestDistance = 1e300;
    for (std::size_t r = 0; r < records.size(); ++r) {
      const double d = crackvis::dem::norm(records[r].at - mid);
      if (!used[r] && records[r].iteration > since && records[r].iteration <= until &&
          d < bestDistance) {
        best = r;
        bestDistance = d;
      }
    }
    INFO("bond " << row.at("bond") << " at step " << step);
    REQUIRE(best < records.size());
    used[best] = 1;
    CHECK(bestDistance < lattice->radius[static_cast<std::size_t>(bond.first)]);
    const std::string recorded = records[best].type == 1 ? "tension" : "shear";
    CHECK(row.at("mode") == recorded);
    // The import matched the same record to the bond (bonds/break_mode),
    // and crackvis's own rule says the same.
    CHECK(row.at("source") == "recorded");
    CHECK(row.at("rule_mode") == recorded);
  }
  CHECK_THAT(fileText(out + "/index.md"),
             Catch::Contains("27 of the 27 breaks have the mode the code recorded") &&
                 Catch::Contains("agrees on 27 of them"));
}

TEST_CASE("crackvis report on ESyS-Particle's and LAMMPS's notched bars writes every table",
          "[cli][report]") {
  TempDir dir;
  for (const std::string code : {"esys", "lammps"}) {
    INFO(code);
    const std::string data = dir.file(code + ".h5");
    REQUIRE(runProcess({kCli, "import", code,
                        std::string(CRACKVIS_TEST_DATA) + "/" + code + "/notched_bar", "-o", data,
                        "-q"})
                .exitCode == 0);
    const std::string out = dir.file(code + "-report");
    REQUIRE(runProcess({kCli, "report", data, "-o", out, "-q"}).exitCode == 0);
    for (const char* table : kTables) {
      CHECK(std::filesystem::exists(out + "/" + table));
    }
    const Table growth = readCsv(out + "/growth.csv");
    REQUIRE(growth.size() > 2);
    // Every bond that broke during the run has a mode; those broken at the
    // first step (a notch) were broken before it.
    const double during =
        number(growth.back(), "broken_bonds") - number(growth.front(), "broken_bonds");
    CHECK(number(growth.back(), "tension_breaks") + number(growth.back(), "shear_breaks") ==
          during);
    CHECK(readCsv(out + "/break_modes.csv").size() == static_cast<std::size_t>(during));
    // The notched bars break in two.
    CHECK(number(growth.back(), "fragments") == 2.0);
    CHECK(number(growth.back(), "main_mean_opening") > 0.0);
    CHECK(isPng(out + "/opening.png"));
  }
}
