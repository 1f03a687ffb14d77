// crackvis generate: a lattice block or a dense random packing written as a
// one-step crackvis-dem file, the starting point of a simulation and the
// sample data of the demo and the tests.
#include <charconv>

#include <fmt/format.h>

#include "commands.hpp"
#include <crackvis/common/pending_file.hpp>
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/partition.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/dem/planted_crack.hpp>
#include <crackvis/dem/random_packing.hpp>

namespace crackvis::cli {
namespace {

struct GenerateOptions {
  std::string packing = "lattice";
  std::string lattice = "fcc";
  int dimension = 3;  // random packings
  std::string radiusRange;
  double solidFraction = 0.55;
  double interactionRange = 1.1;
  int plantedCrack = 0;  // steps of a planted through crack; 0: one intact step
  std::vector<int> sites;
  std::vector<double> box;
  double radius = 1e-3;
  double jitter = 0.0;
  double strength = 1.0;
  std::uint64_t seed = 1;
  std::string output;
  bool quiet = false;
};

Result<dem::BlockSpec> makeSpec(const GenerateOptions& options) {
  auto kind = dem::parseLatticeKind(options.lattice);
  if (!kind) {
    return kind.status();
  }
  const int dimension = dem::dimensionOf(*kind);
  dem::BlockSpec spec;
  spec.kind = *kind;
  spec.radius = options.radius;
  spec.jitter = options.jitter;
  spec.strength = options.strength;
  spec.seed = options.seed;
  const std::vector<int>& counts = options.sites;
  if (!counts.empty()) {
    if (static_cast<int>(counts.size()) != dimension) {
      return invalidArgument(fmt::format("--sites needs {} values for a {}D {} lattice, got {}",
                                         dimension, dimension, options.lattice, counts.size()));
    }
    spec.sites = {counts[0], counts[1], dimension == 3 ? counts[2] : 1};
  } else if (!options.box.empty()) {
    if (static_cast<int>(options.box.size()) != dimension) {
      return invalidArgument(fmt::format("--box needs {} values for a {}D {} lattice, got {}",
                                         dimension, dimension, options.lattice,
                                         options.box.size()));
    }
    spec.sites = dem::sitesForBox(
        *kind, {options.box[0], options.box[1], dimension == 3 ? options.box[2] : 0.0},
        options.radius);
    if (spec.sites[0] < 1 || spec.sites[1] < 1 || (dimension == 3 && spec.sites[2] < 1)) {
      return invalidArgument(
          fmt::format("the box is too small for spheres of radius {}", options.radius));
    }
  }
  return spec;
}

// "RMIN:RMAX" in metres.
Result<std::pair<double, double>> parseRadiusRange(const std::string& text) {
  const auto colon = text.find(':');
  double lo = 0.0;
  double hi = 0.0;
  auto parse = [](std::string_view part, double& value) {
    const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), value);
    return error == std::errc{} && end == part.data() + part.size();
  };
  if (colon == std::string::npos || !parse(std::string_view(text).substr(0, colon), lo) ||
      !parse(std::string_view(text).substr(colon + 1), hi) || !(lo > 0.0) || !(hi >= lo)) {
    return invalidArgument(fmt::format(
        "--radius-range '{}' is not RMIN:RMAX with 0 < RMIN <= RMAX (metres, e.g. 5e-4:1e-3)",
        text));
  }
  return std::pair{lo, hi};
}

// A random packing's box: --box, or 20 largest diameters along each axis.
Result<dem::RandomPackingSpec> makeRandomSpec(const GenerateOptions& options) {
  dem::RandomPackingSpec spec;
  spec.dimension = options.dimension;
  spec.radiusMin = options.radius;
  spec.radiusMax = options.radius;
  if (!options.radiusRange.empty()) {
    auto range = parseRadiusRange(options.radiusRange);
    if (!range) {
      return range.status();
    }
    std::tie(spec.radiusMin, spec.radiusMax) = *range;
  }
  spec.solidFraction = options.solidFraction;
  spec.interactionRange = options.interactionRange;
  spec.strength = options.strength;
  spec.seed = options.seed;
  if (!options.sites.empty()) {
    return invalidArgument("--sites is for lattices; give a random packing's size with --box");
  }
  if (options.box.empty()) {
    const double side = 40.0 * spec.radiusMax;
    spec.box = {side, side, options.dimension == 3 ? side : 0.0};
  } else if (static_cast<int>(options.box.size()) != options.dimension) {
    return invalidArgument(fmt::format("--box needs {} values for a {}D packing, got {}",
                                       options.dimension, options.dimension, options.box.size()));
  } else {
    spec.box = {options.box[0], options.box[1], options.dimension == 3 ? options.box[2] : 0.0};
  }
  CRACKVIS_RETURN_IF_ERROR(dem::validate(spec));
  return spec;
}

struct Generated {
  dem::Lattice lattice;
  std::vector<dem::Vec3> positions;
  std::string summary;
};

Result<Generated> generateLattice(const GenerateOptions& options) {
  auto spec = makeSpec(options);
  if (!spec) {
    return spec.status();
  }
  auto block = dem::generateBlock(*spec);
  if (!block) {
    return block.status();
  }
  std::string summary =
      fmt::format("{} lattice, {} particles, {} bonds, block {:.6g} x {:.6g} x {:.6g} m",
                  options.lattice, block->lattice.particleCount(), block->lattice.bondCount(),
                  block->extent.x, block->extent.y, block->extent.z);
  return Generated{std::move(block->lattice), std::move(block->positions), std::move(summary)};
}

Result<Generated> generateRandom(const GenerateOptions& options) {
  auto spec = makeRandomSpec(options);
  if (!spec) {
    return spec.status();
  }
  ProgressBar progress("generate", 100);
  progress.setEnabled(!options.quiet);
  auto packing = dem::generateRandomPacking(*spec, [&](double done) {
    progress.update(static_cast<std::int64_t>(100.0 * done), "relaxing overlaps");
  });
  progress.finish();
  if (!packing) {
    return packing.status();
  }
  const std::size_t n = packing->lattice.particleCount();
  std::string summary = fmt::format(
      "random {}D packing, {} particles (radius {:.4g}..{:.4g} m), {} bonds (mean coordination "
      "{:.2f}), solid fraction {:.3f}, box {:.6g} x {:.6g} x {:.6g} m",
      spec->dimension, n, spec->radiusMin, spec->radiusMax, packing->lattice.bondCount(),
      n > 0 ? 2.0 * static_cast<double>(packing->lattice.bondCount()) / static_cast<double>(n)
            : 0.0,
      packing->solidFraction, spec->box.x, spec->box.y, spec->box.z);
  return Generated{std::move(packing->lattice), std::move(packing->positions), std::move(summary)};
}

// One intact step, or with --planted-crack the series of a planted through
// crack, written step by step to `path`.
Status writeStepsTo(const std::string& path, const GenerateOptions& options,
                    const Generated& generated) {
  dem::DemMetadata metadata;
  metadata.source = invocation();
  metadata.sourceCode = "crackvis generate";
  metadata.sourceVersion = CRACKVIS_VERSION;
  cracks::describeCells(metadata, generated.lattice);
  auto writer = dem::DemFileWriter::create(path, generated.lattice, metadata);
  if (!writer) {
    return writer.status();
  }
  if (options.plantedCrack <= 0) {
    dem::StepState initial;
    initial.positions = generated.positions;
    initial.bondState.assign(generated.lattice.bondCount(), 0);
    CRACKVIS_RETURN_IF_ERROR(writer->appendStep(initial));
    return writer->close();
  }
  dem::PlantedCrackSpec spec;
  spec.steps = options.plantedCrack;
  spec.seed = options.seed;
  auto crack = dem::PlantedCrack::create(generated.lattice, generated.positions, spec);
  if (!crack) {
    return crack.status();
  }
  ProgressBar progress("generate: planted crack", crack->stepCount());
  progress.setEnabled(!options.quiet);
  for (int k = 0; k < crack->stepCount(); ++k) {
    CRACKVIS_RETURN_IF_ERROR(writer->appendStep(crack->step(k)));
    progress.update(k + 1);
  }
  progress.finish();
  return writer->close();
}

// An existing output is replaced only by a complete file.
Status writeSteps(const GenerateOptions& options, const Generated& generated) {
  PendingFile output(options.output);
  Status status = writeStepsTo(output.path(), options, generated);
  if (status) {
    status = output.commit();
  }
  return output.named(status);
}

int runGenerate(const GenerateOptions& options) {
  auto generated = options.packing == "random" ? generateRandom(options) : generateLattice(options);
  if (!generated) {
    printError("generate", generated.status().message());
    return kExitFailure;
  }
  if (Status status = writeSteps(options, *generated); !status) {
    printError("generate", status.message());
    return kExitFailure;
  }
  if (!options.quiet) {
    std::printf("wrote %s: %s\n", options.output.c_str(), generated->summary.c_str());
  }
  return kExitOk;
}

}  // namespace

Command addGenerateCommand(CLI::App& parent) {
  auto options = std::make_shared<GenerateOptions>();
  auto* command = parent.add_subcommand(
      "generate",
      "Write a lattice block of monodisperse spheres bonded to their nearest neighbours, or a "
      "dense random packing (monodisperse or polydisperse) bonded by an interaction-range rule, "
      "as a one-step crackvis-dem file (all bonds intact).");
  command
      ->add_option("--packing", options->packing,
                   "lattice (--lattice) or random: spheres (disks in 2D) placed at random and "
                   "relaxed until they no longer overlap")
      ->check(CLI::IsMember({"lattice", "random"}))
      ->capture_default_str();
  command->add_option("--lattice", options->lattice, "fcc, hcp (3D) or triangular (2D)")
      ->check(CLI::IsMember({"fcc", "hcp", "triangular"}))
      ->capture_default_str();
  auto* sites = command->add_option(
      "--sites", options->sites,
      "Sites per axis (X Y [Z]). fcc: site planes d/sqrt(2) apart, a block of n cubic unit cells "
      "has 2n+1; hcp: spheres per row, rows per layer, layers; triangular: spheres per row, rows");
  auto* box = command->add_option("--box", options->box,
                                  "Fill a box of this size in metres (X Y [Z]) instead of --sites");
  sites->excludes(box);
  box->excludes(sites);
  auto* radius = command->add_option("-r,--radius", options->radius, "Sphere radius in metres")
                     ->check(CLI::PositiveNumber)
                     ->capture_default_str();
  auto* radiusRange = command->add_option(
      "--radius-range", options->radiusRange,
      "random: radii drawn uniformly from RMIN:RMAX metres (e.g. 5e-4:1e-3, a 1:2 polydisperse "
      "packing) instead of one --radius");
  radiusRange->excludes(radius);
  command->add_option("--dimension", options->dimension, "random: 3 (spheres) or 2 (disks)")
      ->check(CLI::IsMember({2, 3}))
      ->capture_default_str();
  command
      ->add_option("--solid-fraction", options->solidFraction,
                   "random: volume (2D: area) of the spheres over the box's; up to about 0.6 in "
                   "3D and 0.8 in 2D")
      ->check(CLI::Range(0.01, 0.84))
      ->capture_default_str();
  command
      ->add_option("--interaction-range", options->interactionRange,
                   "random: bond every pair closer than this times the sum of their radii")
      ->check(CLI::Range(1.0, 2.0))
      ->capture_default_str();
  command
      ->add_option("--jitter", options->jitter,
                   "Random displacement of each coordinate, as a fraction of the radius")
      ->check(CLI::Range(0.0, 0.49))
      ->capture_default_str();
  command->add_option("--strength", options->strength, "Tensile strength R_n of every bond, N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--seed", options->seed, "Seed of the jitter or the random packing")
      ->capture_default_str();
  command
      ->add_option("--planted-crack", options->plantedCrack,
                   "Write STEPS more steps with a planted through crack (for benchmarks and "
                   "tests): the bonds across the mid-plane x break from the bottom up, reaching "
                   "the top at 3/4 of the steps, the right half moves away by up to one mean bond "
                   "length, and 0.2 % of the bonds break at random elsewhere")
      ->check(CLI::Range(1, 100000));
  command->add_option("-o,--output", options->output, "Output HDF5 file")->required();
  command->add_flag("-q,--quiet", options->quiet, "Print nothing on success, no progress bar");
  command->footer(
      "Examples:\n  crackvis generate --lattice fcc --sites 21 21 21 --radius 0.002 -o block.h5\n"
      "  crackvis generate --packing random --radius-range 5e-4:1e-3 --solid-fraction 0.6 "
      "--box 0.03 0.03 0.03 -o random.h5");
  return {command, [options] {
            if (options->packing == "lattice" && options->sites.empty() && options->box.empty()) {
              // Default: an FCC block of 4 x 4 x 4 cubic cells, or a 20 x 20 2D patch.
              options->sites = dem::dimensionOf(*dem::parseLatticeKind(options->lattice)) == 3
                                   ? std::vector<int>{9, 9, 9}
                                   : std::vector<int>{20, 20};
            }
            return runGenerate(*options);
          }};
}

}  // namespace crackvis::cli
