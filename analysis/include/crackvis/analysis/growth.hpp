// All analyses of one run, step by step, and the crack's growth.
//
// CrackAnalysis is fed each step's input and extracted crack mesh, in step
// order (as the extractors are), and keeps what is incremental: the bond
// states are compared with the last step's once, and what follows breaks
// reads only the new ones; the crack's components weld only the new faces
// (cracks::ComponentTracker); fragments are found again only when a new
// break may have split one; each bond's mode is decided the step it breaks.
// Stepping back (a bond heals) starts them over.
//
// Growth per step: the total crack area, the main crack's (the largest
// component's) area and bounding box, and its front (crackFront): the main
// crack's extent along the in-plane axis it grew along most, and that
// extent's rate of change in time.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <crackvis/analysis/fragments.hpp>
#include <crackvis/analysis/opening.hpp>
#include <crackvis/analysis/orientation.hpp>
#include <crackvis/cracks/extractor.hpp>

namespace crackvis::analysis {

struct AnalysisOptions {
  OpeningOptions opening;
  std::size_t minFragment = 1;  // particles; smaller fragments are dust
  // Fill StepAnalysis::mainNormal at every step. Off, only mainPlane() gives
  // it, for the steps that need it: the second moments of the main crack's
  // every face were half the analyses' work of a step.
  bool mainPlaneEachStep = false;
};

struct StepAnalysis {
  int step = 0;
  double time = 0.0;
  std::size_t broken = 0;
  double totalArea = 0.0;  // all components, m^2 (2D: m)
  std::size_t components = 0;
  bool hasMain = false;
  double mainArea = 0.0;
  dem::Bounds mainBox;
  Vec3 mainNormal;  // zero unless AnalysisOptions::mainPlaneEachStep, or set from mainPlane()
  OpeningSummary mainOpening;
  OpeningSummary allOpening;
  std::size_t fragments = 0;  // of at least minFragment particles
  double largestFragmentShare = 0.0;
  std::size_t tension = 0;  // bonds broken in tension up to this step
  std::size_t shear = 0;
};

class CrackAnalysis {
 public:
  CrackAnalysis(const dem::Lattice& lattice, AnalysisOptions options);

  // `reference`: the configuration openings are measured from (the file's
  // first step); `bondForce` may be empty.
  // `recordedModes`: the file's dem::kBreakModeArray at this step, or empty.
  StepAnalysis analyse(int step, double time, const cracks::StepInput& input,
                       std::span<const Vec3> reference, const CrackMesh& mesh,
                       std::span<const double> recordedModes = {});

  // Every component's primitives, area and box (cracks::ComponentDetail::kAreas):
  // centroids and planes are zero unless `planes` (where the tracker found the
  // components anew); mainPlane() or cracks::componentPlane give them.
  const CrackComponents& components() const { return m_components.current(); }
  // The main crack's centroid and best-fit plane at the step analysed last;
  // `mesh`: the one given to analyse.
  cracks::ComponentPlane mainPlane(const CrackMesh& mesh) const;
  const ElementOpenings& openings() const { return m_openings; }
  // The broken bonds' normals, kept across the steps analysed.
  const BondNormals& normals() const { return m_normals; }
  const Fragments& fragments() const { return m_fragments.current(); }
  const FragmentTracker& fragmentTracker() const { return m_fragments; }
  const BreakModeTracker& modes() const { return m_modes; }
  const AnalysisOptions& options() const { return m_options; }

 private:
  const dem::Lattice& m_lattice;
  AnalysisOptions m_options;
  BondDiffer m_bondDiff;
  std::vector<cracks::Primitive> m_primitives;  // of the step analysed last
  cracks::ComponentTracker m_components;
  ElementOpenings m_openings;
  BondNormals m_normals;
  FragmentTracker m_fragments;
  BreakModeTracker m_modes;
};

struct CrackFront {
  int axis = -1;               // 0 x, 1 y, 2 z; -1: no main crack in any step
  std::vector<double> extent;  // per step, m (0 without a main crack)
  std::vector<double> speed;   // per step, m per unit of time (0 at the first)
};

// The in-plane axes are the world axes other than the one the last main
// crack's normal is closest to (2D: and z): of the last step with a main
// crack and a normal (mainNormal set; `crackvis report` and `info` set the
// last step's, so where bonds healed and the last step has no main crack,
// an earlier step's), or without any, the axis the last main crack's box is
// thinnest along. Of those, the one along which
// the main crack's extent grew most from its first step to its last.
CrackFront crackFront(std::span<const StepAnalysis> steps, int dimension);

std::string axisName(int axis);

// One number per step under a name.
struct NamedSeries {
  std::string name;
  std::vector<double> values;
};

// The per-step crack numbers as series named as the columns of `crackvis
// report`'s growth.csv (total_area, main_area, front_extent, ...), for a
// plot of any one against any other; NaN where a step has no value (the
// main crack's opening before there is a main crack).
std::vector<NamedSeries> crackSeries(std::span<const StepAnalysis> steps, const CrackFront& front);

}  // namespace crackvis::analysis
