// crackvis import: reads what a DEM code wrote (LAMMPS, ESyS-Particle, Yade,
// or a plain CSV/NumPy folder) into a crackvis-dem file, step by step (a live
// one with --follow, beside a run that is still writing).
#include <atomic>
#include <csignal>

#include <fmt/format.h>

#include "commands.hpp"
#include <crackvis/importers/importer.hpp>

namespace crackvis::cli {
namespace {

struct ImportCommandOptions {
  std::string code;
  std::vector<std::string> inputs;
  importers::ImportOptions import;
  int compress = 0;
  bool quiet = false;
  bool follow = false;
  importers::FollowOptions following;
};

Result<std::unique_ptr<importers::StepSource>> openSource(const ImportCommandOptions& options);

// SIGINT or SIGTERM during --follow: the import ends after its next look,
// with every complete step written and the live file closed.
std::atomic<bool> g_stopFollowing{false};
extern "C" void stopFollowing(int) {
  g_stopFollowing = true;
}

int runFollow(ImportCommandOptions& options) {
  if (options.following.untilIdle <= 0.0 && options.following.pid <= 0) {
    std::fprintf(stderr,
                 "crackvis import: following until interrupted (Ctrl-C, SIGTERM); --until-idle "
                 "SECONDS or --pid PID end it by themselves\n");
  }
  std::signal(SIGINT, stopFollowing);
  std::signal(SIGTERM, stopFollowing);
  options.following.stopRequested = [] { return g_stopFollowing.load(); };
  if (!options.quiet) {
    options.following.appended = [&](int index, std::int64_t codeStep, std::size_t broken) {
      std::fprintf(stderr, "\rimport: step %d (code step %lld), broken %zu   ", index,
                   static_cast<long long>(codeStep), broken);
    };
  }
  auto summary = importers::followSeries([&] { return openSource(options); }, options.import,
                                         options.following);
  if (!options.quiet) {
    std::fputc('\n', stderr);
  }
  if (!summary) {
    printError("import", summary.status().message());
    return kExitFailure;
  }
  std::fputs(importers::formatSummary(*summary, options.import).c_str(), stdout);
  return kExitOk;
}

Result<std::unique_ptr<importers::StepSource>> openSource(const ImportCommandOptions& options) {
  if (options.code == "lammps") {
    return importers::openLammps(options.inputs);
  }
  if (options.code == "esys") {
    return importers::openEsys(options.inputs);
  }
  if (options.code == "yade") {
    return importers::openYade(options.inputs);
  }
  return importers::openCsv(options.inputs);
}

int runImport(ImportCommandOptions& options) {
  if (options.import.output.empty() && !options.import.dryRun) {
    printError("import", "give the output file with -o FILE.h5 (or --dry-run to only look)");
    return kExitUsage;
  }
  options.import.invocation = invocation();
  options.import.progress = !options.quiet;
  options.import.storage.deflateLevel = options.compress;
  if (!options.follow && (options.following.untilIdle > 0.0 || options.following.pid > 0)) {
    printError("import", "--until-idle and --pid go with --follow");
    return kExitUsage;
  }
  if (options.follow) {
    return runFollow(options);
  }
  auto source = openSource(options);
  if (!source) {
    printError("import", source.status().message());
    return kExitFailure;
  }
  auto summary = importers::importSeries(**source, options.import);
  if (!summary) {
    printError("import", summary.status().message());
    return kExitFailure;
  }
  std::fputs(importers::formatSummary(*summary, options.import).c_str(), stdout);
  return kExitOk;
}

}  // namespace

Command addImportCommand(CLI::App& parent) {
  auto options = std::make_shared<ImportCommandOptions>();
  auto* command = parent.add_subcommand(
      "import",
      "Read a DEM code's output into a crackvis-dem file, one step at a time.\n"
      "  lammps  dump custom particle files (id type x y z radius ...) and dump local bond\n"
      "          files (compute property/local batom1 batom2 btype), one or many steps each\n"
      "  esys    ESyS-Particle snapshots (CheckPointPrms): <prefix>_t=<step>_0.txt and workers\n"
      "  yade    VTKRecorder output (spheres.<iter>.vtu with 'id', intrs.<iter>.vtp with\n"
      "          'jcfpm') and the JCFpm crack file cracks_<Key>.txt where present\n"
      "  csv     a folder with bonds.csv and particles_<step>.csv or .npy (docs/data-format.md)\n"
      "SOURCE is a folder (searched for those files) or the files themselves. The first\n"
      "imported step fixes the particles and bonds; a bond missing or without cohesion later\n"
      "is broken from then on and never heals.");
  command->add_option("code", options->code, "lammps, esys, yade or csv")
      ->required()
      ->check(CLI::IsMember({"lammps", "esys", "yade", "csv"}));
  command->add_option("source", options->inputs, "Folders or files the code wrote")->required();
  command->add_option("-o,--output", options->import.output, "crackvis-dem file to write");
  command->add_option("-s,--steps", options->import.steps,
                      "Steps A, A:B or A:B:K of the source's saved steps (0-based, inclusive; "
                      "-1 the last; default all)");
  command
      ->add_option("--timestep", options->import.timestep,
                   "Seconds per code step, for sources that write no time (LAMMPS dumps "
                   "without 'dump_modify time yes', Yade)")
      ->check(CLI::PositiveNumber);
  command->add_option("--scalars", options->import.scalarsTable,
                      "A table of per-step scalars (header of names, a step/iter column): "
                      "LAMMPS fix print, Yade plot.saveDataTxt, CSV; a 'time' column sets the "
                      "step times");
  command->add_flag("--partial-scalars", options->import.partialScalars,
                    "Import even when the --scalars table has rows for only some steps (they get "
                    "no table scalars; with a time column, a time on the table's line)");
  command
      ->add_option("--compress", options->compress,
                   "Store per-step arrays chunked with shuffle + deflate at this level (1-9); "
                   "default contiguous, uncompressed")
      ->check(CLI::Range(1, 9));
  command->add_flag("--dry-run", options->import.dryRun,
                    "Read the first and last step, print what an import would write, write "
                    "nothing");
  command->add_flag("-q,--quiet", options->quiet, "No progress bar");
  const char* live = "Following a run that is still writing";
  command
      ->add_flag("--follow", options->follow,
                 "Follow a run that is still writing: look at SOURCE again and again, and "
                 "append each step to a live file (readable while it grows: crackvis-client "
                 "and the browser page show each step as it lands) as soon as its files are "
                 "complete. Ends on --until-idle, --pid, Ctrl-C or SIGTERM, with every step "
                 "written")
      ->group(live);
  command
      ->add_option("--until-idle", options->following.untilIdle,
                   "With --follow: end after this many seconds without a new step")
      ->check(CLI::PositiveNumber)
      ->group(live);
  command
      ->add_option("--pid", options->following.pid,
                   "With --follow: end once the DEM code's process PID has ended")
      ->check(CLI::PositiveNumber)
      ->group(live);
  command
      ->add_option("--settle", options->following.settle,
                   "With --follow: seconds the files must rest before the newest step counts "
                   "as complete (a later step always completes it)")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str()
      ->group(live);
  return {command, [options] { return runImport(*options); }};
}

}  // namespace crackvis::cli
