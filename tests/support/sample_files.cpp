#include "support/sample_files.hpp"

#include <cmath>
#include <stdexcept>

#include <crackvis/dem/planted_crack.hpp>
#include <crackvis/dem/random_packing.hpp>

namespace crackvis::testing {

SampleData makeSample(int dimension, int steps, bool optionalArrays) {
  dem::BlockSpec spec;
  spec.kind = dimension == 3 ? dem::LatticeKind::kFcc : dem::LatticeKind::kTriangular;
  spec.sites = dimension == 3 ? std::array<int, 3>{5, 3, 3} : std::array<int, 3>{8, 5, 1};
  spec.radius = 0.002;
  spec.jitter = 0.2;
  spec.seed = 7;
  auto block = dem::generateBlock(spec);
  if (!block) {
    throw std::runtime_error(block.status().message());
  }
  SampleData sample;
  sample.lattice = block->lattice;
  for (size_t b = 0; b < sample.lattice.bondCount(); ++b) {
    sample.lattice.strength[b] = 10.0 + 0.37 * static_cast<double>(b % 11);
  }
  const size_t m = sample.lattice.bondCount();
  for (int k = 0; k < steps; ++k) {
    dem::StepState step;
    step.time = 1e-4 * k;
    const double stretch = 1.0 + 0.01 * k;
    for (const dem::Vec3& p : block->positions) {
      step.positions.push_back({p.x * stretch, p.y, p.z});
    }
    step.bondState.assign(m, 0);
    const size_t broken = static_cast<size_t>(k) * m / (2 * static_cast<size_t>(steps));
    for (size_t b = 0; b < broken; ++b) {
      step.bondState[b] = 1;
    }
    if (optionalArrays) {
      for (size_t i = 0; i < step.positions.size(); ++i) {
        step.velocities.push_back({0.05f * static_cast<float>(k), static_cast<float>(i) * 1e-3f,
                                   dimension == 3 ? -0.25f : 0.0f});
      }
      for (size_t b = 0; b < m; ++b) {
        step.bondForce.push_back(step.bondState[b] ? 0.0f : std::sin(static_cast<float>(b + k)));
      }
    }
    sample.steps.push_back(std::move(step));
  }
  return sample;
}

void writeSample(const std::string& path, const SampleData& sample) {
  auto writer =
      dem::DemFileWriter::create(path, sample.lattice, dem::metadataFrom("crackvis tests"));
  if (!writer) {
    throw std::runtime_error(writer.status().message());
  }
  for (const auto& step : sample.steps) {
    if (Status status = writer->appendStep(step); !status) {
      throw std::runtime_error(status.message());
    }
  }
  if (Status status = writer->close(); !status) {
    throw std::runtime_error(status.message());
  }
}

namespace {

SampleData plantCrack(const dem::Lattice& lattice, std::vector<dem::Vec3> positions, int steps,
                      double scatter) {
  dem::PlantedCrackSpec planted;
  planted.steps = steps;
  planted.scatter = scatter;
  auto crack = dem::PlantedCrack::create(lattice, std::move(positions), planted);
  if (!crack) {
    throw std::runtime_error(crack.status().message());
  }
  SampleData sample{lattice, {}};
  for (int k = 0; k < crack->stepCount(); ++k) {
    sample.steps.push_back(crack->step(k));
  }
  return sample;
}

}  // namespace

void writePlantedRandomPacking(const std::string& path, int steps, double scatter) {
  dem::RandomPackingSpec spec;
  spec.box = {0.008, 0.005, 0.005};
  spec.radiusMin = 3e-4;
  spec.radiusMax = 3e-4;
  auto packing = dem::generateRandomPacking(spec);
  if (!packing) {
    throw std::runtime_error(packing.status().message());
  }
  writeSample(path, plantCrack(packing->lattice, packing->positions, steps, scatter));
}

SampleData writePlantedLattice(const std::string& path, int steps, std::array<int, 3> sites) {
  dem::BlockSpec spec;
  spec.sites = sites;
  auto block = dem::generateBlock(spec);
  if (!block) {
    throw std::runtime_error(block.status().message());
  }
  SampleData sample = plantCrack(block->lattice, block->positions, steps, 0.0);
  writeSample(path, sample);
  return sample;
}

SampleData writeSampleFile(const std::string& path, int dimension, int steps) {
  SampleData sample = makeSample(dimension, steps);
  writeSample(path, sample);
  return sample;
}

}  // namespace crackvis::testing
