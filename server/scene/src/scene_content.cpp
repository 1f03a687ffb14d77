#include <algorithm>
#include <cmath>

#include <crackvis/cracks/lattice_cells.hpp>
#include <crackvis/scene/scene_content.hpp>

namespace crackvis::scene {
namespace {

// A flag of primitive k from a cell array (absent array: `otherwise`).
bool flagOf(const cracks::AttributeArray* array, std::size_t k, bool otherwise) {
  if (array == nullptr || k >= array->values.size()) {
    return otherwise;
  }
  return array->values[k] != 0.0;
}

}  // namespace

// In FCC the third layer shows through the gaps of the first two along
// <111>, hence three layers. Deeper particles are hidden; impostors write
// their depth, so the GPU's early depth test cannot skip them and every
// hidden sphere would cost its fragments.
std::vector<dem::ParticleIndex> visibleParticles(const pipeline::ParticlesDescription& particles,
                                                 const SceneInput& input) {
  const std::size_t n = input.step.positions.size();
  const auto& bonds = input.lattice->bonds;
  std::vector<std::uint8_t> keep(n, 1);
  if (!(particles.opacity < 1.0 || particles.clip || bonds.empty() ||
        input.step.bondState.size() != bonds.size())) {
    std::vector<int> degree(n, 0);
    std::fill(keep.begin(), keep.end(), 0);
    for (std::size_t b = 0; b < bonds.size(); ++b) {
      const auto i = static_cast<std::size_t>(bonds[b].first);
      const auto j = static_cast<std::size_t>(bonds[b].second);
      ++degree[i];
      ++degree[j];
      if (input.step.bondState[b] != 0) {
        keep[i] = keep[j] = 1;
      }
    }
    const int most = n > 0 ? *std::max_element(degree.begin(), degree.end()) : 0;
    for (std::size_t i = 0; i < n; ++i) {
      keep[i] = keep[i] != 0 || degree[i] < most ? 1 : 0;
    }
    for (std::uint8_t layer = 2; layer <= 3; ++layer) {
      for (const dem::Bond& bond : bonds) {
        auto& a = keep[static_cast<std::size_t>(bond.first)];
        auto& c = keep[static_cast<std::size_t>(bond.second)];
        if (a != 0 && a < layer && c == 0) {
          c = layer;
        } else if (c != 0 && c < layer && a == 0) {
          a = layer;
        }
      }
    }
  }
  std::vector<dem::ParticleIndex> visible;
  for (std::size_t i = 0; i < n; ++i) {
    if (keep[i] != 0) {
      visible.push_back(static_cast<dem::ParticleIndex>(i));
    }
  }
  return visible;
}

std::vector<double> particleValues(const pipeline::ParticlesDescription& particles,
                                   const SceneInput& input) {
  const std::size_t n = input.step.positions.size();
  std::vector<double> values(n, 0.0);
  switch (particles.colourBy) {
    case pipeline::ParticleColourBy::kRadius:
      std::copy_n(input.step.radius.begin(), std::min(n, input.step.radius.size()), values.begin());
      break;
    case pipeline::ParticleColourBy::kDisplacement:
      for (std::size_t i = 0; i < n && i < input.initialPositions.size(); ++i) {
        values[i] = dem::norm(input.step.positions[i] - input.initialPositions[i]);
      }
      break;
    case pipeline::ParticleColourBy::kVelocity:
      for (std::size_t i = 0; i < n && i < input.velocities.size(); ++i) {
        const auto& v = input.velocities[i];
        values[i] = std::sqrt(double{v[0]} * v[0] + double{v[1]} * v[1] + double{v[2]} * v[2]);
      }
      break;
    case pipeline::ParticleColourBy::kDamage: {
      std::vector<int> bonds(n, 0);
      std::vector<int> broken(n, 0);
      for (std::size_t b = 0; b < input.lattice->bonds.size(); ++b) {
        for (auto end : {input.lattice->bonds[b].first, input.lattice->bonds[b].second}) {
          ++bonds[static_cast<std::size_t>(end)];
          broken[static_cast<std::size_t>(end)] += input.step.bondState[b] != 0 ? 1 : 0;
        }
      }
      for (std::size_t i = 0; i < n; ++i) {
        values[i] = bonds[i] > 0 ? static_cast<double>(broken[i]) / bonds[i] : 0.0;
      }
      break;
    }
    case pipeline::ParticleColourBy::kExtra:
      std::copy_n(input.particleExtra.begin(), std::min(n, input.particleExtra.size()),
                  values.begin());
      break;
    case pipeline::ParticleColourBy::kSolid:
      break;
  }
  return values;
}

cracks::CrackMesh selectPrimitives(const cracks::CrackMesh& mesh,
                                   const std::function<bool(std::size_t)>& keep) {
  cracks::CrackMesh out;
  out.dimension = mesh.dimension;
  out.points = mesh.points;
  out.pointData = mesh.pointData;
  std::vector<std::size_t> kept;
  std::size_t k = 0;
  for (std::int32_t v : mesh.vertices) {
    if (keep(k)) {
      out.vertices.push_back(v);
      kept.push_back(k);
    }
    ++k;
  }
  auto copyList = [&](const cracks::PrimitiveList& from, cracks::PrimitiveList& to,
                      const std::vector<std::uint8_t>* types) {
    for (std::size_t i = 0; i < from.size(); ++i, ++k) {
      if (!keep(k)) {
        continue;
      }
      to.addRange(from.connectivity.begin() + from.offsets[i],
                  from.connectivity.begin() + from.offsets[i + 1]);
      if (types != nullptr) {
        out.volumeCellTypes.push_back((*types)[i]);
      }
      kept.push_back(k);
    }
  };
  copyList(mesh.lines, out.lines, nullptr);
  copyList(mesh.polygons, out.polygons, nullptr);
  copyList(mesh.volumeCells, out.volumeCells, &mesh.volumeCellTypes);
  for (const cracks::AttributeArray& array : mesh.cellData) {
    cracks::AttributeArray selected{array.name, array.type, array.components, {}};
    const auto c = static_cast<std::size_t>(array.components);
    for (std::size_t i : kept) {
      selected.values.insert(selected.values.end(), array.values.begin() + i * c,
                             array.values.begin() + (i + 1) * c);
    }
    out.cellData.push_back(std::move(selected));
  }
  return out;
}

CrackLayers crackLayers(const pipeline::PipelineDescription& d, const cracks::CrackMesh& mesh) {
  const cracks::AttributeArray* state = mesh.findCellData("bond_state");
  const cracks::AttributeArray* inconsistent = mesh.findCellData("inconsistent");
  CrackLayers layers;
  layers.cracks = selectPrimitives(mesh, [&](std::size_t k) {
    return flagOf(state, k, true) && !flagOf(inconsistent, k, false);
  });
  if (d.showInconsistent && inconsistent != nullptr) {
    layers.marks =
        selectPrimitives(mesh, [&](std::size_t k) { return flagOf(inconsistent, k, false); });
  }
  if (d.showDecomposition && state != nullptr) {
    layers.intact = selectPrimitives(mesh, [&](std::size_t k) {
      return !flagOf(state, k, true) && !flagOf(inconsistent, k, false);
    });
  }
  return layers;
}

std::vector<dem::BondIndex> decompositionBonds(const SceneInput& input) {
  if (input.decomposition == nullptr) {
    return {};
  }
  const cracks::LatticeDecomposition& decomposition = *input.decomposition;
  std::vector<std::uint8_t> used(decomposition.graph().bondCount(), 0);
  for (const cracks::LatticeCell& cell : decomposition.cells()) {
    const auto& shape = cracks::shapeOf(cell.type);
    for (std::size_t e = 0; e < shape.edges.size(); ++e) {
      used[static_cast<std::size_t>(decomposition.bondOf(cell, static_cast<int>(e)))] = 1;
    }
  }
  std::vector<dem::BondIndex> bonds;
  for (std::size_t b = 0; b < used.size(); ++b) {
    if (used[b] != 0) {
      bonds.push_back(static_cast<dem::BondIndex>(b));
    }
  }
  return bonds;
}

BondLines bondLines(const pipeline::BondsDescription& d, const SceneInput& input) {
  BondLines lines;
  if (d.show == pipeline::BondSelection::kNone) {
    return lines;
  }
  for (std::size_t b = 0; b < input.lattice->bonds.size(); ++b) {
    const bool broken = input.step.bondState[b] != 0;
    if (d.show == pipeline::BondSelection::kBroken && !broken) {
      continue;
    }
    double value = broken ? 1.0 : 0.0;
    if (d.colourBy == pipeline::BondColourBy::kForce && !input.step.bondForce.empty()) {
      value = input.step.bondForce[b];
    } else if (d.colourBy == pipeline::BondColourBy::kBreakStep && !input.step.breakStep.empty()) {
      value = input.step.breakStep[b];
    } else if (d.colourBy == pipeline::BondColourBy::kExtra && b < input.bondExtra.size()) {
      value = input.bondExtra[b];
    }
    lines.bonds.push_back(static_cast<dem::BondIndex>(b));
    lines.values.push_back(value);
  }
  return lines;
}

}  // namespace crackvis::scene
