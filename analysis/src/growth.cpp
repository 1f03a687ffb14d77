#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <tbb/parallel_invoke.h>

#include <crackvis/analysis/growth.hpp>

namespace crackvis::analysis {

CrackAnalysis::CrackAnalysis(const dem::Lattice& lattice, AnalysisOptions options)
    : m_lattice(lattice),
      m_options(options),
      m_components(cracks::ComponentDetail::kAreas),
      m_normals(lattice.dimension, options.opening.smoothingRadius) {}

StepAnalysis CrackAnalysis::analyse(int step, double time, const cracks::StepInput& input,
                                    std::span<const Vec3> reference, const CrackMesh& mesh,
                                    std::span<const double> recordedModes) {
  StepAnalysis out;
  out.step = step;
  out.time = time;
  const BondDiff& diff = m_bondDiff.update(input.bondState);
  out.broken = diff.broken;
  // Four trackers that share nothing but their (read-only) inputs, side by
  // side: on cuboid A each is a fraction of a millisecond, so one after
  // another they left the second core idle for most of a step. The
  // openings' bond part (each element's normal, opening and slip) needs the
  // normals, not the components, so it follows them beside the components;
  // where the elements lie (area, centroid, component) is placed after.
  // Each one's result is the same whichever thread runs it.
  m_primitives = cracks::surfacePrimitives(mesh);
  const CrackComponents* tracked = nullptr;
  const Fragments* fragmentsNow = nullptr;
  tbb::parallel_invoke(
      [&] {
        tracked = &m_components.update(mesh, !input.referencePositions.empty(), m_primitives);
      },
      [&] {
        m_normals.update(m_lattice.bonds, diff, input.bondState, reference);
        measureBondOpenings(mesh, m_primitives, m_lattice.bonds, reference, input.positions,
                            m_normals, m_openings);
      },
      [&] {
        fragmentsNow = &m_fragments.update(m_lattice.bonds, input.bondState, m_lattice.radius,
                                           mesh.dimension, &diff);
      },
      [&] {
        m_modes.update(step, m_lattice.bonds, diff, input.bondState, reference, input.positions,
                       input.bondForce, recordedModes);
      });
  const CrackComponents& components = *tracked;
  out.components = components.components.size();
  for (const cracks::CrackComponent& c : components.components) {
    out.totalArea += c.area;
  }
  if (!components.components.empty()) {
    const cracks::CrackComponent& main = components.components.front();
    out.hasMain = true;
    out.mainArea = main.area;
    out.mainBox = main.box;
    if (m_options.mainPlaneEachStep) {
      out.mainNormal = mainPlane(mesh).normal;
    }
  }
  // The faces' areas and centroids from the components' pass, where it
  // measured these primitives (it kept the surface).
  placeOpenings(mesh, m_primitives, components, m_components.extents(), m_openings);
  out.mainOpening = summariseOpening(m_openings, 0);
  out.allOpening = summariseOpening(m_openings, -1);
  out.fragments = fragmentsNow->countAtLeast(m_options.minFragment);
  out.largestFragmentShare = fragmentsNow->largestShare();
  out.tension = m_modes.count(BreakMode::kTension);
  out.shear = m_modes.count(BreakMode::kShear);
  return out;
}

cracks::ComponentPlane CrackAnalysis::mainPlane(const CrackMesh& mesh) const {
  return cracks::componentPlane(mesh, components(), 0);
}

namespace {

double along(const dem::Vec3& v, int axis) {
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

double extentOf(const StepAnalysis& s, int axis) {
  return s.hasMain ? along(s.mainBox.hi, axis) - along(s.mainBox.lo, axis) : 0.0;
}

}  // namespace

CrackFront crackFront(std::span<const StepAnalysis> steps, int dimension) {
  CrackFront front;
  const auto first = std::find_if(steps.begin(), steps.end(), [](auto& s) { return s.hasMain; });
  const auto last = std::find_if(steps.rbegin(), steps.rend(), [](auto& s) { return s.hasMain; });
  if (first == steps.end()) {
    front.extent.assign(steps.size(), 0.0);
    front.speed.assign(steps.size(), 0.0);
    return front;
  }
  // The normal of the last main crack that has one; else (no caller asked
  // for a plane) the axis its box is thinnest along.
  const auto planed = std::find_if(steps.rbegin(), steps.rend(), [](auto& s) {
    return s.hasMain && dem::dot(s.mainNormal, s.mainNormal) > 0.0;
  });
  int normalAxis = 0;
  for (int axis = 1; axis < dimension; ++axis) {
    const bool closer = planed != steps.rend()
                            ? std::abs(along(planed->mainNormal, axis)) >
                                  std::abs(along(planed->mainNormal, normalAxis))
                            : along(last->mainBox.hi - last->mainBox.lo, axis) <
                                  along(last->mainBox.hi - last->mainBox.lo, normalAxis);
    normalAxis = closer ? axis : normalAxis;
  }
  double bestGrowth = -1.0;
  for (int axis = 0; axis < dimension; ++axis) {
    if (axis == normalAxis) {
      continue;
    }
    const double growth = extentOf(*last, axis) - extentOf(*first, axis);
    if (growth > bestGrowth) {
      bestGrowth = growth;
      front.axis = axis;
    }
  }
  for (std::size_t k = 0; k < steps.size(); ++k) {
    front.extent.push_back(extentOf(steps[k], front.axis));
    const double dt = k > 0 ? steps[k].time - steps[k - 1].time : 0.0;
    front.speed.push_back(dt > 0.0 ? (front.extent[k] - front.extent[k - 1]) / dt : 0.0);
  }
  return front;
}

std::string axisName(int axis) {
  return axis == 0 ? "x" : axis == 1 ? "y" : axis == 2 ? "z" : "none";
}

namespace {

// A main-crack opening figure, NaN before the main crack has an element with a bond.
double mainOpening(const StepAnalysis& s, double OpeningSummary::*figure) {
  return s.mainOpening.elements > 0 ? s.mainOpening.*figure
                                    : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

std::vector<NamedSeries> crackSeries(std::span<const StepAnalysis> steps, const CrackFront& front) {
  using Pick = double (*)(const StepAnalysis&);
  const std::pair<const char*, Pick> columns[] = {
      {"total_area", [](const StepAnalysis& s) { return s.totalArea; }},
      {"components", [](const StepAnalysis& s) { return static_cast<double>(s.components); }},
      {"main_area", [](const StepAnalysis& s) { return s.mainArea; }},
      {"main_mean_opening",
       [](const StepAnalysis& s) { return mainOpening(s, &OpeningSummary::meanOpening); }},
      {"main_max_opening",
       [](const StepAnalysis& s) { return mainOpening(s, &OpeningSummary::maxOpening); }},
      {"main_mean_slip",
       [](const StepAnalysis& s) { return mainOpening(s, &OpeningSummary::meanSlip); }},
      {"fragments", [](const StepAnalysis& s) { return static_cast<double>(s.fragments); }},
      {"largest_fragment_share", [](const StepAnalysis& s) { return s.largestFragmentShare; }},
      {"tension_breaks", [](const StepAnalysis& s) { return static_cast<double>(s.tension); }},
      {"shear_breaks", [](const StepAnalysis& s) { return static_cast<double>(s.shear); }},
  };
  std::vector<NamedSeries> series;
  for (const auto& [name, pick] : columns) {
    NamedSeries& out = series.emplace_back(NamedSeries{name, {}});
    for (const StepAnalysis& s : steps) {
      out.values.push_back(pick(s));
    }
  }
  const auto perStep = [&](const std::vector<double>& values) {
    return values.size() == steps.size()
               ? values
               : std::vector<double>(steps.size(), std::numeric_limits<double>::quiet_NaN());
  };
  // The front after the areas, as growth.csv orders its columns.
  series.insert(series.begin() + 3, {NamedSeries{"front_extent", perStep(front.extent)},
                                     NamedSeries{"front_speed", perStep(front.speed)}});
  return series;
}

}  // namespace crackvis::analysis
