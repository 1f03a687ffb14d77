// crackvis export: the specimen itself as a ParaView time series, to load
// beside the crack series of `extract`: particles (points with a vertex
// each, radius, id, group, velocities and the per-particle extras) and,
// with --bonds, the bonds (lines with their state, break step, notch flag,
// force and per-bond extras) as a second part of each step.
#include <filesystem>

#include <fmt/format.h>

#include "commands.hpp"
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/crack_mesh.hpp>
#include <crackvis/cracks/mesh_writers.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/step_range.hpp>

namespace crackvis::cli {
namespace {

namespace fs = std::filesystem;

struct ExportOptions {
  std::string file;
  std::string output;
  std::string steps;
  bool particles = false;
  bool bonds = false;
  bool quiet = false;
};

cracks::AttributeArray attribute(const std::string& name, cracks::AttributeType type,
                                 int components, std::vector<double> values) {
  cracks::AttributeArray array;
  array.name = name;
  array.type = type;
  array.components = components;
  array.values = std::move(values);
  return array;
}

template <typename T>
std::vector<double> asDoubles(const std::vector<T>& values) {
  return {values.begin(), values.end()};
}

void addExtras(const std::vector<dem::ExtraArray>& extras, dem::ExtraOwner owner,
               std::vector<cracks::AttributeArray>& out) {
  for (const dem::ExtraArray& extra : extras) {
    if (extra.owner == owner) {
      out.push_back(
          attribute(extra.name, cracks::AttributeType::kFloat64, extra.components, extra.values));
    }
  }
}

cracks::CrackMesh particleMesh(const dem::Lattice& lattice, const dem::StepState& step) {
  cracks::CrackMesh mesh;
  mesh.dimension = lattice.dimension;
  mesh.points = step.positions;
  mesh.vertices.resize(step.positions.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    mesh.vertices[i] = static_cast<std::int32_t>(i);
  }
  using cracks::AttributeType;
  mesh.pointData.push_back(attribute("radius", AttributeType::kFloat64, 1, lattice.radius));
  if (!lattice.particleId.empty()) {
    mesh.pointData.push_back(
        attribute("id", AttributeType::kFloat64, 1, asDoubles(lattice.particleId)));
  }
  if (!lattice.particleGroup.empty()) {
    mesh.pointData.push_back(
        attribute("group", AttributeType::kInt32, 1, asDoubles(lattice.particleGroup)));
  }
  if (!step.velocities.empty()) {
    std::vector<double> flat;
    flat.reserve(step.velocities.size() * 3);
    for (const auto& v : step.velocities) {
      flat.insert(flat.end(), v.begin(), v.end());
    }
    mesh.pointData.push_back(attribute("velocity", AttributeType::kFloat32, 3, std::move(flat)));
  }
  addExtras(lattice.extras, dem::ExtraOwner::kParticles, mesh.pointData);
  addExtras(step.extras, dem::ExtraOwner::kParticles, mesh.pointData);
  return mesh;
}

cracks::CrackMesh bondMesh(const dem::Lattice& lattice, const dem::StepState& step,
                           const std::vector<std::int32_t>& breakStep) {
  cracks::CrackMesh mesh;
  mesh.dimension = lattice.dimension;
  mesh.points = step.positions;
  for (const dem::Bond& bond : lattice.bonds) {
    mesh.lines.add({bond.first, bond.second});
  }
  using cracks::AttributeType;
  mesh.cellData.push_back(attribute("broken", AttributeType::kInt32, 1, asDoubles(step.bondState)));
  mesh.cellData.push_back(attribute("break_step", AttributeType::kInt32, 1, asDoubles(breakStep)));
  std::vector<double> notch(lattice.bondCount());
  for (std::size_t b = 0; b < notch.size(); ++b) {
    notch[b] = lattice.cutAtStart(b) ? 1.0 : 0.0;
  }
  mesh.cellData.push_back(attribute("cut_at_start", AttributeType::kInt32, 1, std::move(notch)));
  if (!lattice.strength.empty()) {
    mesh.cellData.push_back(attribute("strength", AttributeType::kFloat64, 1, lattice.strength));
  }
  if (!step.bondForce.empty()) {
    mesh.cellData.push_back(
        attribute("bond_force", AttributeType::kFloat32, 1, asDoubles(step.bondForce)));
  }
  addExtras(lattice.extras, dem::ExtraOwner::kBonds, mesh.cellData);
  addExtras(step.extras, dem::ExtraOwner::kBonds, mesh.cellData);
  return mesh;
}

Status exportSeries(const ExportOptions& options) {
  if (fs::path(options.output).extension() != ".pvd") {
    return invalidArgument(
        fmt::format("{}: the output is a ParaView collection: name it OUT.pvd", options.output));
  }
  auto reader = dem::DemFileReader::openGuarded(options.file);
  if (!reader) {
    return reader.status();
  }
  auto lattice = reader->readLattice();
  if (!lattice) {
    return lattice.status();
  }
  auto breakStep = reader->readBreakSteps();
  if (!breakStep) {
    return breakStep.status();
  }
  auto steps =
      dem::parseStepRange(options.steps.empty() ? "0:-1" : options.steps, reader->stepCount());
  if (!steps) {
    return steps.status();
  }
  const fs::path output(options.output);
  const std::string stem = output.stem().string();
  const fs::path folder = output.parent_path() / stem;
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) {
    return failedPrecondition(
        fmt::format("{}: cannot create folder ({})", folder.string(), error.message()));
  }
  std::vector<cracks::CollectionEntry> entries;
  ProgressBar progress("export", static_cast<std::int64_t>(steps->size()));
  progress.setEnabled(!options.quiet);
  for (std::size_t k = 0; k < steps->size(); ++k) {
    const int step = (*steps)[k];
    auto state = reader->readStep(step);
    if (!state) {
      return state.status();
    }
    if (options.particles) {
      const std::string relative = fmt::format("{}/{}_particles_{:06d}.vtp", stem, stem, step);
      CRACKVIS_RETURN_IF_ERROR(cracks::writeVtkXml(particleMesh(*lattice, *state),
                                                   (output.parent_path() / relative).string()));
      entries.push_back({state->time, relative});
    }
    if (options.bonds) {
      const std::string relative = fmt::format("{}/{}_bonds_{:06d}.vtp", stem, stem, step);
      CRACKVIS_RETURN_IF_ERROR(cracks::writeVtkXml(bondMesh(*lattice, *state, *breakStep),
                                                   (output.parent_path() / relative).string()));
      entries.push_back({state->time, relative});
    }
    progress.update(static_cast<std::int64_t>(k + 1), fmt::format("step {}", step));
  }
  progress.finish();
  return cracks::writePvd(entries, options.output);
}

int runExport(ExportOptions& options) {
  if (!options.particles && !options.bonds) {
    options.particles = true;
  }
  if (Status status = exportSeries(options); !status) {
    printError("export", status.message());
    return kExitFailure;
  }
  if (!options.quiet) {
    std::printf("wrote %s\n", options.output.c_str());
  }
  return kExitOk;
}

}  // namespace

Command addExportCommand(CLI::App& parent) {
  auto options = std::make_shared<ExportOptions>();
  auto* command = parent.add_subcommand(
      "export",
      "Write the specimen as a ParaView time series (OUT.pvd and a folder OUT/ of .vtp files), to "
      "open beside the crack series of 'crackvis extract': particles as points with radius, id, "
      "group, velocity and the file's extra arrays (show them with Point Gaussian or Glyph); "
      "with --bonds also the bonds as lines with 'broken', 'break_step', 'cut_at_start' and the "
      "per-bond arrays, a second part of each step.\n"
      "  crackvis export run.h5 --particles --bonds -s 0:-1:10 -o specimen.pvd");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command->add_option("-o,--output", options->output, "OUT.pvd")->required();
  command->add_option("-s,--steps", options->steps,
                      "Steps A, A:B or A:B:K (inclusive; -1 the last; default all)");
  command->add_flag("--particles", options->particles,
                    "Write the particles (the default when neither is given)");
  command->add_flag("--bonds", options->bonds, "Write the bonds");
  command->add_flag("-q,--quiet", options->quiet, "No progress bar");
  return {command, [options] { return runExport(*options); }};
}

}  // namespace crackvis::cli
