// crackvis generate: a lattice block written as a one-step crackvis-dem file,
// the starting point of a simulation and the sample data of the demo.
#include <fmt/format.h>

#include "commands.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>

namespace crackvis::cli {
namespace {

struct GenerateOptions {
  std::string lattice = "fcc";
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

int runGenerate(const GenerateOptions& options) {
  auto spec = makeSpec(options);
  if (!spec) {
    printError("generate", spec.status().message());
    return kExitFailure;
  }
  auto block = dem::generateBlock(*spec);
  if (!block) {
    printError("generate", block.status().message());
    return kExitFailure;
  }
  auto writer = dem::DemFileWriter::create(options.output, block->lattice, {invocation(), "SI"});
  if (!writer) {
    printError("generate", writer.status().message());
    return kExitFailure;
  }
  dem::StepState initial;
  initial.positions = block->positions;
  initial.bondState.assign(block->lattice.bondCount(), 0);
  if (Status status = writer->appendStep(initial); !status) {
    printError("generate", status.message());
    return kExitFailure;
  }
  if (Status status = writer->close(); !status) {
    printError("generate", status.message());
    return kExitFailure;
  }
  if (!options.quiet) {
    std::printf("wrote %s: %s lattice, %zu particles, %zu bonds, block %.6g x %.6g x %.6g m\n",
                options.output.c_str(), options.lattice.c_str(), block->lattice.particleCount(),
                block->lattice.bondCount(), block->extent.x, block->extent.y, block->extent.z);
  }
  return kExitOk;
}

}  // namespace

Command addGenerateCommand(CLI::App& parent) {
  auto options = std::make_shared<GenerateOptions>();
  auto* command = parent.add_subcommand(
      "generate",
      "Write a lattice block of monodisperse spheres, bonded to their nearest neighbours, as a "
      "one-step crackvis-dem file (all bonds intact).");
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
  command->add_option("-r,--radius", options->radius, "Sphere radius in metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--jitter", options->jitter,
                   "Random displacement of each coordinate, as a fraction of the radius")
      ->check(CLI::Range(0.0, 0.49))
      ->capture_default_str();
  command->add_option("--strength", options->strength, "Tensile strength R_n of every bond, N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--seed", options->seed, "Seed of the jitter")->capture_default_str();
  command->add_option("-o,--output", options->output, "Output HDF5 file")->required();
  command->add_flag("-q,--quiet", options->quiet, "Print nothing on success");
  command->footer(
      "Example: crackvis generate --lattice fcc --sites 21 21 21 --radius 0.002 -o block.h5");
  return {command, [options] {
            if (options->sites.empty() && options->box.empty()) {
              // Default: an FCC block of 4 x 4 x 4 cubic cells, or a 20 x 20 2D patch.
              options->sites = dem::dimensionOf(*dem::parseLatticeKind(options->lattice)) == 3
                                   ? std::vector<int>{9, 9, 9}
                                   : std::vector<int>{20, 20};
            }
            return runGenerate(*options);
          }};
}

}  // namespace crackvis::cli
