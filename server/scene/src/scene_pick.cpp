#include <cmath>
#include <limits>
#include <optional>
#include <span>

#include <fmt/format.h>

#include <crackvis/scene_model/scene_content.hpp>
#include <crackvis/scene_model/scene_pick.hpp>

namespace crackvis::scene {
namespace {

using dem::Vec3;

constexpr double kNone = std::numeric_limits<double>::infinity();

// The description hides the side of a clipping plane its normal points to.
bool kept(const std::optional<pipeline::ClipPlane>& clip, const Vec3& point) {
  return !clip || dem::dot(point - clip->origin, clip->normal) <= 0.0;
}

// The ray parameter where it enters the sphere (or leaves it, when the entry
// is clipped away and the far side shows through the cut), kNone if neither.
double hitSphere(const Ray& ray, const Vec3& centre, double radius,
                 const std::optional<pipeline::ClipPlane>& clip) {
  const Vec3 to = ray.origin - centre;
  const double a = dem::dot(ray.direction, ray.direction);
  const double b = dem::dot(to, ray.direction);
  const double c = dem::dot(to, to) - radius * radius;
  const double discriminant = b * b - a * c;
  if (discriminant < 0.0 || a == 0.0) {
    return kNone;
  }
  const double root = std::sqrt(discriminant);
  for (const double t : {(-b - root) / a, (-b + root) / a}) {
    if (t > 0.0 && kept(clip, ray.origin + t * ray.direction)) {
      return t;
    }
  }
  return kNone;
}

// Möller-Trumbore: the ray parameter of its hit with triangle abc, or kNone.
double hitTriangle(const Ray& ray, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a;
  const Vec3 e2 = c - a;
  const Vec3 p = cracks::cross(ray.direction, e2);
  const double det = dem::dot(e1, p);
  if (std::abs(det) < 1e-300) {
    return kNone;
  }
  const Vec3 s = ray.origin - a;
  const double u = dem::dot(s, p) / det;
  if (u < 0.0 || u > 1.0) {
    return kNone;
  }
  const Vec3 q = cracks::cross(s, e1);
  const double v = dem::dot(ray.direction, q) / det;
  if (v < 0.0 || u + v > 1.0) {
    return kNone;
  }
  const double t = dem::dot(e2, q) / det;
  return t > 0.0 ? t : kNone;
}

// A polygon as a fan of triangles; a convex cell (tetrahedron, pyramid) as
// every triangle of its corners: the first one the ray meets lies on the
// cell's boundary, where it enters.
double hitPrimitive(const Ray& ray, const std::vector<Vec3>& points, const std::int32_t* ids,
                    std::size_t count, bool volume) {
  double best = kNone;
  auto test = [&](std::size_t i, std::size_t j, std::size_t k) {
    best = std::min(best, hitTriangle(ray, points[static_cast<std::size_t>(ids[i])],
                                      points[static_cast<std::size_t>(ids[j])],
                                      points[static_cast<std::size_t>(ids[k])]));
  };
  if (!volume) {
    for (std::size_t k = 1; k + 1 < count; ++k) {
      test(0, k, k + 1);
    }
    return best;
  }
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t j = i + 1; j < count; ++j) {
      for (std::size_t k = j + 1; k < count; ++k) {
        test(i, j, k);
      }
    }
  }
  return best;
}

struct Hit {
  double t = kNone;
  std::int64_t index = -1;
};

Hit nearestParticle(const pipeline::PipelineDescription& d, const SceneInput& input,
                    const Ray& ray) {
  Hit hit;
  if (!d.particles.visible) {
    return hit;
  }
  for (const dem::ParticleIndex i : visibleParticles(d.particles, input)) {
    const auto k = static_cast<std::size_t>(i);
    const double t =
        hitSphere(ray, input.step.positions[k], input.step.radius[k], d.particles.clip);
    if (t < hit.t) {
      hit = {t, static_cast<std::int64_t>(i)};
    }
  }
  return hit;
}

// The crack layer as drawn: its primitives and, per primitive, its index in
// the extracted mesh (the cell data of the drawn layer is the mesh's).
Hit nearestCrack(const cracks::CrackMesh& layer, const pipeline::CracksDescription& cracks,
                 const Ray& ray) {
  Hit hit;
  const std::size_t first = layer.vertices.size() + layer.lines.size();
  auto scan = [&](const cracks::PrimitiveList& list, std::size_t offset, bool volume) {
    for (std::size_t k = 0; k < list.size(); ++k) {
      const auto begin = static_cast<std::size_t>(list.offsets[k]);
      const auto count = static_cast<std::size_t>(list.offsets[k + 1]) - begin;
      const double t =
          hitPrimitive(ray, layer.points, list.connectivity.data() + begin, count, volume);
      if (t < hit.t && kept(cracks.clip, ray.origin + t * ray.direction)) {
        hit = {t, static_cast<std::int64_t>(offset + k)};
      }
    }
  };
  scan(layer.polygons, first, false);
  scan(layer.volumeCells, first + layer.polygons.size(), true);
  return hit;
}

void addParticleValues(const pipeline::PipelineDescription& d, const SceneInput& input,
                       std::size_t i, std::vector<PickedValue>& values) {
  values.push_back({"radius", input.step.radius[i], "m"});
  using By = pipeline::ParticleColourBy;
  const std::pair<By, PickedValue> quantities[] = {
      {By::kDisplacement, {"displacement", 0.0, "m"}},
      {By::kVelocity, {"speed", 0.0, "m/s"}},
      {By::kDamage, {"damage (broken bonds / bonds)", 0.0, ""}}};
  for (const auto& [by, value] : quantities) {
    if (by == By::kDisplacement && input.initialPositions.empty()) {
      continue;
    }
    if (by == By::kVelocity && input.velocities.empty()) {
      continue;
    }
    PickedValue v = value;
    v.value = particleValues(by, input)[i];
    values.push_back(v);
  }
  if (!input.particleExtra.empty()) {
    values.push_back(
        {d.particles.colourByExtra.empty() ? "extra" : "extra:" + d.particles.colourByExtra,
         static_cast<double>(input.particleExtra[i]), ""});
  }
}

std::string unitOf(const std::string& array) {
  return array.ends_with("force") ? "N" : array == "opening" || array == "slip" ? "m" : "";
}

// The points of primitive `cell` (VTK order) of `layer`.
std::span<const std::int32_t> cornersOf(const cracks::CrackMesh& layer, std::size_t cell) {
  const std::size_t polygons = layer.vertices.size() + layer.lines.size();
  const cracks::PrimitiveList& list =
      cell < polygons + layer.polygons.size() ? layer.polygons : layer.volumeCells;
  const std::size_t k = cell - polygons - (&list == &layer.polygons ? 0 : layer.polygons.size());
  const auto begin = static_cast<std::size_t>(list.offsets[k]);
  return {list.connectivity.data() + begin, static_cast<std::size_t>(list.offsets[k + 1]) - begin};
}

// The element's own values (cell data), and where a method keeps them on
// the element's corners (cell cut: the broken bond each corner lies on)
// those of the corner nearest the picked point.
void addCrackValues(const cracks::CrackMesh& layer, std::size_t cell, const Vec3& point,
                    std::vector<PickedValue>& values) {
  for (const cracks::AttributeArray& array : layer.cellData) {
    if (array.components == 1 && cell < array.tupleCount()) {
      values.push_back({array.name, array.values[cell], unitOf(array.name)});
    }
  }
  std::int32_t nearest = -1;
  double best = kNone;
  for (const std::int32_t corner : cornersOf(layer, cell)) {
    const double d = dem::norm(layer.points[static_cast<std::size_t>(corner)] - point);
    if (d < best) {
      best = d;
      nearest = corner;
    }
  }
  for (const cracks::AttributeArray& array : layer.pointData) {
    if (nearest >= 0 && array.components == 1 &&
        static_cast<std::size_t>(nearest) < array.tupleCount()) {
      values.push_back({array.name + " (nearest corner)",
                        array.values[static_cast<std::size_t>(nearest)], unitOf(array.name)});
    }
  }
}

}  // namespace

PickResult pick(const pipeline::PipelineDescription& d, const SceneInput& input, const Ray& ray) {
  PickResult result;
  if (input.lattice == nullptr) {
    return result;
  }
  const Hit particle = nearestParticle(d, input, ray);
  std::optional<cracks::CrackMesh> layer;
  Hit crack;
  if (d.cracks.visible && input.cracks != nullptr) {
    layer = crackLayers(d, *input.cracks).cracks;
    crack = nearestCrack(*layer, d.cracks, ray);
  }
  if (particle.t == kNone && crack.t == kNone) {
    return result;
  }
  const bool isParticle = particle.t <= crack.t;
  const Hit& hit = isParticle ? particle : crack;
  result.kind = isParticle ? PickedKind::kParticle : PickedKind::kCrack;
  result.index = hit.index;
  result.point = ray.origin + hit.t * ray.direction;
  if (isParticle) {
    addParticleValues(d, input, static_cast<std::size_t>(hit.index), result.values);
  } else {
    addCrackValues(*layer, static_cast<std::size_t>(hit.index), result.point, result.values);
  }
  return result;
}

const char* pickedKindName(PickedKind kind) {
  switch (kind) {
    case PickedKind::kParticle:
      return "particle";
    case PickedKind::kCrack:
      return "crack element";
    case PickedKind::kNothing:
      break;
  }
  return "";
}

std::string describePick(const PickResult& result) {
  if (result.kind == PickedKind::kNothing) {
    return "nothing there";
  }
  std::string text = fmt::format("{} {} at ({:.6g}, {:.6g}, {:.6g}) m", pickedKindName(result.kind),
                                 result.index, result.point.x, result.point.y, result.point.z);
  const char* separator = ": ";
  for (const PickedValue& v : result.values) {
    text += fmt::format("{}{} {:.6g}{}{}", separator, v.name, v.value, v.unit.empty() ? "" : " ",
                        v.unit);
    separator = ", ";
  }
  return text;
}

}  // namespace crackvis::scene
