// Factories of the four methods (one .cpp each), for extractor.cpp. The
// cell-based ones take the cells of a triangulation for packings that are no
// lattice (triangulated_extractor.cpp); without them they use the lattice's.
#pragma once

#include <crackvis/cracks/extractor.hpp>

namespace crackvis::cracks {

std::unique_ptr<CrackExtractor> makeCellAttribute(const BondGraph& graph, int dimension,
                                                  const ExtractOptions& options,
                                                  const ExplicitCells* cells = nullptr);
std::unique_ptr<CrackExtractor> makeCellCut(const BondGraph& graph, int dimension,
                                            const ExtractOptions& options,
                                            const ExplicitCells* cells = nullptr);
std::unique_ptr<CrackExtractor> makeLocalVoronoi(const BondGraph& graph, int dimension,
                                                 const ExtractOptions& options);
std::unique_ptr<CrackExtractor> makeCellCentre(const BondGraph& graph, int dimension,
                                               const ExtractOptions& options,
                                               const ExplicitCells* cells = nullptr);

// Any method on the cells of a triangulation of the reference configuration,
// for packings whose bonds span no lattice.
std::unique_ptr<CrackExtractor> makeTriangulated(Method method, const BondGraph& graph,
                                                 int dimension, const ExtractOptions& options);

// Primitives made by one block of work items. Work is cut into blocks of a
// fixed size (not per thread), blocks run on all cores, and their outputs are
// appended in block order: the result is the same for any thread count.
struct PrimitiveBlock {
  std::vector<std::int32_t> vertices;
  PrimitiveList lines;
  PrimitiveList polygons;
  std::vector<std::int32_t> vertexTags, lineTags, polygonTags;  // e.g. the bond of each

  void clear() {
    vertices.clear();
    lines.clear();
    polygons.clear();
    vertexTags.clear();
    lineTags.clear();
    polygonTags.clear();
  }
};

inline constexpr std::size_t kBlockSize = 512;

// Runs fill(first, last, block) over [0, count) in blocks and appends the
// blocks to `mesh` (and their tags to `tags`, in VTK order). `blocks` is
// scratch kept by the caller so its buffers are reused from step to step.
template <typename Fill>
void fillInBlocks(std::size_t count, std::vector<PrimitiveBlock>& blocks, CrackMesh& mesh,
                  std::vector<std::int32_t>& tags, Fill&& fill);

void appendBlocks(std::vector<PrimitiveBlock>& blocks, CrackMesh& mesh,
                  std::vector<std::int32_t>& tags);

}  // namespace crackvis::cracks

#include <tbb/parallel_for.h>

namespace crackvis::cracks {

template <typename Fill>
void fillInBlocks(std::size_t count, std::vector<PrimitiveBlock>& blocks, CrackMesh& mesh,
                  std::vector<std::int32_t>& tags, Fill&& fill) {
  const std::size_t blockCount = (count + kBlockSize - 1) / kBlockSize;
  blocks.resize(blockCount);
  tbb::parallel_for(std::size_t{0}, blockCount, [&](std::size_t k) {
    blocks[k].clear();
    fill(k * kBlockSize, std::min(count, (k + 1) * kBlockSize), blocks[k]);
  });
  appendBlocks(blocks, mesh, tags);
}

}  // namespace crackvis::cracks
