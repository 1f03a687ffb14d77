#include <algorithm>
#include <numeric>
#include <set>

#include <crackvis/cracks/cut_cases.hpp>

namespace crackvis::cracks {
namespace {

bool isBroken(std::uint8_t mask, int edge) {
  return (mask >> edge) & 1u;
}

// Cut edges of component `inside`, linked around it through shared faces.
std::vector<std::uint8_t> enclosureCycle(CellType type, std::uint8_t insideNodes) {
  const CellShape& shape = shapeOf(type);
  auto inside = [&](int node) { return ((insideNodes >> node) & 1u) != 0; };
  std::vector<int> cutEdges;
  for (int e = 0; e < shape.edgeCount; ++e) {
    const auto& edge = shape.edges[static_cast<std::size_t>(e)];
    if (inside(edge[0]) != inside(edge[1])) {
      cutEdges.push_back(e);
    }
  }
  if (type == CellType::kTriangle) {
    return {cutEdges.begin(), cutEdges.end()};  // two edges: a segment
  }
  // Link the cut edges that are consecutive around a face.
  std::vector<std::vector<int>> links(static_cast<std::size_t>(shape.edgeCount));
  for (int f = 0; f < shape.faceCount; ++f) {
    const auto& face = shape.faces[static_cast<std::size_t>(f)];
    const int size = shape.faceSizes[static_cast<std::size_t>(f)];
    std::vector<int> onFace;
    for (int k = 0; k < size; ++k) {
      const int e = localEdge(type, face[static_cast<std::size_t>(k)],
                              face[static_cast<std::size_t>((k + 1) % size)]);
      if (std::find(cutEdges.begin(), cutEdges.end(), e) != cutEdges.end()) {
        onFace.push_back(e);
      }
    }
    for (std::size_t k = 0; k + 1 < onFace.size(); k += 2) {
      links[static_cast<std::size_t>(onFace[k])].push_back(onFace[k + 1]);
      links[static_cast<std::size_t>(onFace[k + 1])].push_back(onFace[k]);
    }
  }
  std::vector<std::uint8_t> cycle;
  int previous = -1;
  int current = cutEdges.front();
  for (std::size_t step = 0; step < cutEdges.size(); ++step) {
    cycle.push_back(static_cast<std::uint8_t>(current));
    const auto& next = links[static_cast<std::size_t>(current)];
    if (next.size() != 2) {
      return {};  // not a simple cycle: cannot happen for lattice cells (tested)
    }
    const int following = next[0] != previous ? next[0] : next[1];
    previous = current;
    current = following;
  }
  return current == cutEdges.front() ? cycle : std::vector<std::uint8_t>{};
}

CutCase buildCase(CellType type, std::uint8_t mask) {
  const CellShape& shape = shapeOf(type);
  CutCase result;
  int count = 0;
  const auto label = intactComponents(type, mask, count);
  if (count >= 2) {
    std::vector<int> sizes(static_cast<std::size_t>(count), 0);
    for (int k = 0; k < shape.nodeCount; ++k) {
      ++sizes[static_cast<std::size_t>(label[static_cast<std::size_t>(k)])];
    }
    // Keep the largest component unenclosed; ties keep node 0's component.
    int kept = label[0];
    for (int c = 0; c < count; ++c) {
      if (sizes[static_cast<std::size_t>(c)] > sizes[static_cast<std::size_t>(kept)]) {
        kept = c;
      }
    }
    for (int c = 0; c < count; ++c) {
      if (c == kept) {
        continue;
      }
      std::uint8_t insideNodes = 0;
      for (int k = 0; k < shape.nodeCount; ++k) {
        if (label[static_cast<std::size_t>(k)] == c) {
          insideNodes = static_cast<std::uint8_t>(insideNodes | (1u << k));
        }
      }
      result.polygons.push_back({enclosureCycle(type, insideNodes), insideNodes});
    }
  }
  // Broken edges inside one component: the crack ends in this cell.
  std::set<std::pair<int, int>> lines;
  for (int e = 0; e < shape.edgeCount; ++e) {
    const auto& edge = shape.edges[static_cast<std::size_t>(e)];
    if (!isBroken(mask, e) || label[edge[0]] != label[edge[1]]) {
      continue;
    }
    bool joined = false;
    for (int f = 0; f < shape.faceCount; ++f) {
      const auto& face = shape.faces[static_cast<std::size_t>(f)];
      const int size = shape.faceSizes[static_cast<std::size_t>(f)];
      std::vector<int> faceEdges;
      for (int k = 0; k < size; ++k) {
        faceEdges.push_back(localEdge(type, face[static_cast<std::size_t>(k)],
                                      face[static_cast<std::size_t>((k + 1) % size)]));
      }
      if (type == CellType::kTriangle ||
          std::find(faceEdges.begin(), faceEdges.end(), e) == faceEdges.end()) {
        continue;
      }
      for (int other : faceEdges) {
        if (other != e && isBroken(mask, other)) {
          lines.insert({std::min(e, other), std::max(e, other)});
          joined = true;
        }
      }
    }
    if (!joined) {
      result.points.push_back(static_cast<std::uint8_t>(e));
    }
  }
  for (const auto& [a, b] : lines) {
    result.lines.push_back({static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b)});
  }
  return result;
}

std::vector<CutCase> buildTable(CellType type) {
  const int patterns = 1 << shapeOf(type).edgeCount;
  std::vector<CutCase> table;
  table.reserve(static_cast<std::size_t>(patterns));
  for (int mask = 0; mask < patterns; ++mask) {
    table.push_back(buildCase(type, static_cast<std::uint8_t>(mask)));
  }
  return table;
}

}  // namespace

std::array<int, kMaxCellNodes> intactComponents(CellType type, std::uint8_t brokenMask,
                                                int& count) {
  const CellShape& shape = shapeOf(type);
  std::array<int, kMaxCellNodes> parent{};
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      x = parent[static_cast<std::size_t>(x)];
    }
    return x;
  };
  for (int e = 0; e < shape.edgeCount; ++e) {
    if (!isBroken(brokenMask, e)) {
      const auto& edge = shape.edges[static_cast<std::size_t>(e)];
      parent[static_cast<std::size_t>(find(edge[0]))] = find(edge[1]);
    }
  }
  // Labels 0..count-1 in order of first appearance.
  std::array<int, kMaxCellNodes> label{-1, -1, -1, -1, -1};
  std::array<int, kMaxCellNodes> rootLabel{-1, -1, -1, -1, -1};
  count = 0;
  for (int k = 0; k < shape.nodeCount; ++k) {
    const int root = find(k);
    if (rootLabel[static_cast<std::size_t>(root)] < 0) {
      rootLabel[static_cast<std::size_t>(root)] = count++;
    }
    label[static_cast<std::size_t>(k)] = rootLabel[static_cast<std::size_t>(root)];
  }
  return label;
}

const CutCase& cutCase(CellType type, std::uint8_t brokenMask) {
  static const std::vector<CutCase> kTriangle = buildTable(CellType::kTriangle);
  static const std::vector<CutCase> kTetrahedron = buildTable(CellType::kTetrahedron);
  static const std::vector<CutCase> kPyramid = buildTable(CellType::kPyramid);
  switch (type) {
    case CellType::kTriangle:
      return kTriangle[brokenMask & 0x7u];
    case CellType::kTetrahedron:
      return kTetrahedron[brokenMask & 0x3Fu];
    case CellType::kPyramid:
      break;
  }
  return kPyramid[brokenMask];
}

}  // namespace crackvis::cracks
