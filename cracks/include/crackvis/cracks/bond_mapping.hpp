// How many of a step's broken bonds became a surface element: a method that
// silently maps few broken bonds to faces (a packing that is no lattice,
// validation refusing faces) misleads more than one that fails. Every run
// reports this fraction; below kMappedWarning it warns, naming the likely
// cause.
//
// A broken bond of the file (index < M; virtual bonds of a triangulation do
// not count) is mapped when:
//  - local Voronoi, cell centre: a surface primitive (polygon; 2D segment not
//    flagged inconsistent) carries its bond_id;
//  - cell cut: a surface primitive uses its point (point data bond_id);
//  - cell attribute: a cell of the decomposition holds it.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <crackvis/cracks/extractor.hpp>

namespace crackvis::cracks {

inline constexpr double kMappedWarning = 0.95;

struct BondMapping {
  std::size_t broken = 0;
  std::size_t mapped = 0;
  double fraction() const {
    return broken == 0 ? 1.0 : static_cast<double>(mapped) / static_cast<double>(broken);
  }
};

BondMapping mapBrokenBonds(const CrackMesh& mesh, std::span<const std::uint8_t> bondState,
                           const CrackExtractor& extractor);

// The broken bonds that separate the two largest pieces the intact bonds
// hold together (the halves of a through crack): a mask over the bonds.
std::vector<std::uint8_t> separatingBonds(const BondGraph& graph,
                                          std::span<const std::uint8_t> bondState);

// The main crack, measured through the bonds that separate the halves:
//  - mapped: of those bonds, how many became surface elements (as above);
//  - area, largestShare: the main crack's area (the surface primitives of
//    separating bonds) and the part of it that lies in the largest component.
//    Cells (cell attribute) carry no bonds and have no area of their own:
//    area 0, and largestShare is the part of the separating bonds that are
//    edges of cells of the largest component, of those that are edges of any.
struct MainCrack {
  BondMapping mapped;
  double area = 0.0;
  double largestShare = 0.0;
};
MainCrack measureMainCrack(const CrackMesh& mesh, std::span<const std::uint8_t> separating,
                           const CrackExtractor& extractor);

// The likely cause of a low fraction, as a phrase for a warning ("the bonds
// span no lattice ..."); empty when the fraction is at least kMappedWarning.
std::string diagnoseMapping(const BondMapping& mapping, const CrackExtractor& extractor,
                            const BondGraph& graph, int dimension, std::span<const double> radius,
                            const ExtractOptions& options);

}  // namespace crackvis::cracks
