#include <algorithm>
#include <cmath>

#include <crackvis/cracks/convex_cell.hpp>

namespace crackvis::cracks {
namespace {

enum Side : std::int8_t { kIn = -1, kOn = 0, kOut = 1 };

Side sideOf(double distance, double tolerance) {
  return distance < -tolerance ? kIn : (distance > tolerance ? kOut : kOn);
}

}  // namespace

void ConvexCell::reset(Vec3 lo, Vec3 hi) {
  m_vertices = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  // Counter-clockwise seen from outside.
  m_faceVertices = {0, 4, 7, 3, 1, 2, 6, 5, 0, 1, 5, 4, 3, 7, 6, 2, 0, 3, 2, 1, 4, 5, 6, 7};
  m_faceStart = {0, 4, 8, 12, 16, 20, 24};
  m_labels = {-1, -2, -3, -4, -5, -6};
}

bool ConvexCell::clip(Vec3 normal, double offset, std::int32_t label, double tolerance) {
  const std::size_t vertexCount = m_vertices.size();
  m_distance.resize(vertexCount);
  m_side.resize(vertexCount);
  bool anyOut = false;
  bool anyKept = false;
  for (std::size_t v = 0; v < vertexCount; ++v) {
    m_distance[v] = dem::dot(normal, m_vertices[v]) - offset;
    const Side side = sideOf(m_distance[v], tolerance);
    m_side[v] = side;
    anyOut = anyOut || side == kOut;
    anyKept = anyKept || side == kIn;
  }
  if (!anyOut) {
    return true;  // the plane misses the cell or only touches it
  }
  if (!anyKept) {
    m_vertices.clear();
    m_faceVertices.clear();
    m_faceStart.assign(1, 0);
    m_labels.clear();
    return false;
  }
  // Surviving vertices keep their order; crossing edges get new vertices.
  m_remap.assign(vertexCount, -1);
  m_newVertices.clear();
  m_cap.clear();
  for (std::size_t v = 0; v < vertexCount; ++v) {
    if (m_side[v] != kOut) {
      m_remap[v] = static_cast<std::int32_t>(m_newVertices.size());
      m_newVertices.push_back(m_vertices[v]);
      if (m_side[v] == kOn) {
        m_cap.push_back(m_remap[v]);
      }
    }
  }
  m_edgePoints.clear();
  auto crossing = [&](std::int32_t a, std::int32_t b) {
    const std::int32_t lo = std::min(a, b);
    const std::int32_t hi = std::max(a, b);
    for (const auto& known : m_edgePoints) {
      if (known[0] == lo && known[1] == hi) {
        return known[2];
      }
    }
    const double da = m_distance[static_cast<std::size_t>(lo)];
    const double db = m_distance[static_cast<std::size_t>(hi)];
    const double t = da / (da - db);
    const Vec3 pa = m_vertices[static_cast<std::size_t>(lo)];
    const Vec3 pb = m_vertices[static_cast<std::size_t>(hi)];
    const auto index = static_cast<std::int32_t>(m_newVertices.size());
    m_newVertices.push_back(pa + t * (pb - pa));
    m_edgePoints.push_back({lo, hi, index});
    m_cap.push_back(index);
    return index;
  };
  m_newStart.assign(1, 0);
  m_newFaceVertices.clear();
  m_newLabels.clear();
  m_capEdges.clear();
  for (std::size_t f = 0; f < m_labels.size(); ++f) {
    const auto cycle = face(f);
    const std::size_t before = m_newFaceVertices.size();
    // A face with no vertex outside is kept as it is.
    bool faceOut = false;
    for (std::int32_t v : cycle) {
      faceOut = faceOut || m_side[static_cast<std::size_t>(v)] == kOut;
    }
    if (!faceOut) {
      for (std::int32_t v : cycle) {
        m_newFaceVertices.push_back(m_remap[static_cast<std::size_t>(v)]);
      }
      m_newStart.push_back(static_cast<std::int32_t>(m_newFaceVertices.size()));
      m_newLabels.push_back(m_labels[f]);
      continue;
    }
    // The kept part of a convex face is one run; the outside part another.
    // The last vertex kept before the outside run (exit) and the first after
    // it (enter) bound the face's new edge exit -> enter on the plane; the
    // cap runs along it the other way.
    std::int32_t exit = -1;
    std::int32_t enter = -1;
    bool skipping = false;
    for (std::size_t k = 0; k < cycle.size(); ++k) {
      const std::int32_t a = cycle[k];
      const std::int32_t b = cycle[(k + 1) % cycle.size()];
      const auto sa = static_cast<Side>(m_side[static_cast<std::size_t>(a)]);
      const auto sb = static_cast<Side>(m_side[static_cast<std::size_t>(b)]);
      if (sa != kOut) {
        m_newFaceVertices.push_back(m_remap[static_cast<std::size_t>(a)]);
        if (skipping) {
          enter = m_newFaceVertices.back();
          skipping = false;
        }
      }
      if ((sa == kIn && sb == kOut) || (sa == kOut && sb == kIn)) {
        m_newFaceVertices.push_back(crossing(a, b));
        if (sa == kOut) {
          enter = m_newFaceVertices.back();
          skipping = false;
        }
      }
      if (sa != kOut && sb == kOut) {
        exit = m_newFaceVertices.back();
        skipping = true;
      }
    }
    if (skipping && m_newFaceVertices.size() > before) {
      enter = m_newFaceVertices[before];  // the outside run wrapped around the start
    }
    if (exit >= 0 && enter >= 0 && exit != enter) {
      m_capEdges.push_back({enter, exit});
    }
    if (m_newFaceVertices.size() - before >= 3) {
      m_newStart.push_back(static_cast<std::int32_t>(m_newFaceVertices.size()));
      m_newLabels.push_back(m_labels[f]);
    } else {
      m_newFaceVertices.resize(before);  // the face lay outside or touched the plane only
    }
  }
  // m_cap holds each on-plane and crossing vertex once.
  if (m_cap.size() >= 3) {
    const std::size_t start = m_newFaceVertices.size();
    // Chain the cap edges into one cycle.
    bool chained = m_capEdges.size() == m_cap.size();
    if (chained) {
      std::int32_t current = m_capEdges.front().first;
      for (std::size_t k = 0; k < m_capEdges.size() && chained; ++k) {
        m_newFaceVertices.push_back(current);
        const auto next = std::find_if(m_capEdges.begin(), m_capEdges.end(),
                                       [&](const auto& edge) { return edge.first == current; });
        chained = next != m_capEdges.end();
        current = chained ? next->second : -1;
      }
      chained = chained && current == m_capEdges.front().first;
    }
    if (!chained) {
      m_newFaceVertices.resize(start);
      orderByAngle(normal);
    }
    m_newStart.push_back(static_cast<std::int32_t>(m_newFaceVertices.size()));
    m_newLabels.push_back(label);
  }
  std::swap(m_vertices, m_newVertices);
  std::swap(m_faceStart, m_newStart);
  std::swap(m_faceVertices, m_newFaceVertices);
  std::swap(m_labels, m_newLabels);
  return true;
}

void ConvexCell::orderByAngle(Vec3 normal) {
  Vec3 centre{};
  for (std::int32_t v : m_cap) {
    centre = centre + m_newVertices[static_cast<std::size_t>(v)];
  }
  centre = (1.0 / static_cast<double>(m_cap.size())) * centre;
  const Vec3 n = (1.0 / dem::norm(normal)) * normal;
  const Vec3 helper = std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 u = cross(n, helper);
  const Vec3 w = cross(n, u);
  m_byAngle.clear();
  for (std::int32_t v : m_cap) {
    const Vec3 d = m_newVertices[static_cast<std::size_t>(v)] - centre;
    m_byAngle.push_back({std::atan2(dem::dot(d, w), dem::dot(d, u)), v});
  }
  std::sort(m_byAngle.begin(), m_byAngle.end());
  for (const auto& entry : m_byAngle) {
    m_newFaceVertices.push_back(entry.second);
  }
}

std::int32_t ConvexCell::findFace(std::int32_t label) const {
  for (std::size_t f = 0; f < m_labels.size(); ++f) {
    if (m_labels[f] == label) {
      return static_cast<std::int32_t>(f);
    }
  }
  return -1;
}

double ConvexCell::faceArea(std::size_t f) const {
  const auto cycle = face(f);
  return polygonArea(m_vertices, cycle.data(), cycle.size());
}

double ConvexCell::volume() const {
  // Sum of pyramids from an interior reference point over the faces.
  if (m_vertices.empty()) {
    return 0.0;
  }
  Vec3 centre{};
  for (const Vec3& v : m_vertices) {
    centre = centre + v;
  }
  centre = (1.0 / static_cast<double>(m_vertices.size())) * centre;
  double sum = 0.0;
  for (std::size_t f = 0; f < m_labels.size(); ++f) {
    const auto cycle = face(f);
    const Vec3 a = m_vertices[static_cast<std::size_t>(cycle[0])] - centre;
    for (std::size_t k = 1; k + 1 < cycle.size(); ++k) {
      const Vec3 b = m_vertices[static_cast<std::size_t>(cycle[k])] - centre;
      const Vec3 c = m_vertices[static_cast<std::size_t>(cycle[k + 1])] - centre;
      sum += dem::dot(a, cross(b, c));
    }
  }
  return sum / 6.0;
}

}  // namespace crackvis::cracks
