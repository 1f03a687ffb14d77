#include "methods.hpp"

namespace crackvis::cracks {
namespace {

void appendList(const PrimitiveList& from, PrimitiveList& to) {
  const auto base = static_cast<std::int32_t>(to.connectivity.size());
  to.connectivity.insert(to.connectivity.end(), from.connectivity.begin(), from.connectivity.end());
  for (std::size_t k = 1; k < from.offsets.size(); ++k) {
    to.offsets.push_back(base + from.offsets[k]);
  }
}

}  // namespace

void appendBlocks(std::vector<PrimitiveBlock>& blocks, CrackMesh& mesh,
                  std::vector<std::int32_t>& tags) {
  // VTK order: all vertices, then all lines, then all polygons.
  std::vector<std::int32_t> vertexTags, lineTags, polygonTags;
  std::size_t vertices = 0;
  std::size_t lines = 0;
  std::size_t polygons = 0;
  for (const PrimitiveBlock& block : blocks) {
    vertices += block.vertices.size();
    lines += block.lines.connectivity.size();
    polygons += block.polygons.connectivity.size();
  }
  mesh.vertices.reserve(vertices);
  mesh.lines.connectivity.reserve(lines);
  mesh.polygons.connectivity.reserve(polygons);
  for (PrimitiveBlock& block : blocks) {
    mesh.vertices.insert(mesh.vertices.end(), block.vertices.begin(), block.vertices.end());
    vertexTags.insert(vertexTags.end(), block.vertexTags.begin(), block.vertexTags.end());
  }
  for (PrimitiveBlock& block : blocks) {
    appendList(block.lines, mesh.lines);
    lineTags.insert(lineTags.end(), block.lineTags.begin(), block.lineTags.end());
  }
  for (PrimitiveBlock& block : blocks) {
    appendList(block.polygons, mesh.polygons);
    polygonTags.insert(polygonTags.end(), block.polygonTags.begin(), block.polygonTags.end());
  }
  tags = std::move(vertexTags);
  tags.insert(tags.end(), lineTags.begin(), lineTags.end());
  tags.insert(tags.end(), polygonTags.begin(), polygonTags.end());
}

}  // namespace crackvis::cracks
