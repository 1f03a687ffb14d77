// A crackvis-dem file read through crackvis-data: what a renderer needs,
// typed as in crackvis::dem, moving only the arrays a view uses.
//
// open() describes the file once (one round trip) and checks that it is
// crackvis-dem v1 with the expected dtypes and shapes. The bond list is read
// once, with the first step asked for (or, with OpenOptions, alongside the
// description), and kept; each further step is one
// Read of its positions and bond states, plus the optional arrays a view
// colours by (velocities, bond forces) when asked for. Not thread-safe: one
// per session.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/dem/model.hpp>
#include <crackvis/dem/spatial_index.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dataservice {

struct RemoteStep {
  int index = 0;
  double time = 0.0;
  std::vector<dem::Vec3> positions;     // [N]
  std::vector<std::uint8_t> bondState;  // [M], dem::BondState values
  // Only when asked for and the step has them (crackvis-dem: optional).
  std::vector<std::array<float, 3>> velocities;  // [N], m/s
  std::vector<float> bondForce;                  // [M], N
  // A per-particle extra array (crackvis-dem v1.1), when asked for: row-major
  // [N, particleExtraComponents] (1 or 3).
  std::vector<double> particleExtra;
  int particleExtraComponents = 1;
  std::vector<double> bondExtra;  // the same per bond: [M, bondExtraComponents]
  int bondExtraComponents = 1;
};

// The optional per-step arrays readStep should bring along.
struct StepExtras {
  bool velocities = false;
  bool bondForce = false;
  // The NAME of a per-particle extra array (/steps/K/extra/particles/NAME,
  // else the constant /extra/particles/NAME); empty: none. A file without it
  // is FAILED_PRECONDITION naming the ones it has.
  std::string particleExtra;
  std::string bondExtra;  // likewise, extra/bonds/NAME
  friend bool operator==(const StepExtras&, const StepExtras&) = default;
};

struct OpenOptions {
  // Ask for the bond list together with the description, for a view that
  // will show a step: the list (most of a first view's bytes) streams while
  // the description is answered and checked, instead of after it. It is
  // taken on first use (readStep, bonds()) while the step's Read starts; a
  // server that allows one stream refuses that Read, which is then asked for
  // again once the list is in. If the server refused or cut the list's
  // stream, the list is read again when needed (bonds(), the next
  // readStep). Dropping the file before cancels it, with at most the
  // stream's window (16 MiB) received.
  bool prefetchBondList = false;
  // With prefetchBondList: the particles' radii as a second slab of the same
  // Read (a render view reads them next; radii() takes them). One round trip
  // less for the view; `crackvis bench transfer` leaves them out, its first
  // view being the step and the bond list.
  bool prefetchRadii = false;
};

class RemoteDemFile {
 public:
  static Result<RemoteDemFile> open(const DataClient& client, const std::string& file,
                                    const OpenOptions& options = {});

  const std::string& file() const { return m_file; }
  const FileDescription& description() const { return *m_description; }
  int dimension() const { return m_dimension; }
  // The root attribute time_unit is "iteration": steps' times are the code's
  // step numbers (it wrote no time).
  bool timeInIterations() const { return m_timeInIterations; }
  // Whether the file is a live one (crackvis-dem v1.2's appendable layout).
  bool appendable() const { return m_appendable; }
  // A live file whose writer still had it open when last described
  // (/steps/writing; a killed writer leaves it set).
  bool beingWritten() const { return m_beingWritten; }
  // Describes the file again: a live file's writer may have committed steps
  // since. True when there are more steps now. FAILED_PRECONDITION when the
  // name now holds another file (another run_id, other N or M, fewer steps,
  // another first step): a reader never mixes two files' steps.
  Result<bool> refresh();
  std::int64_t particleCount() const { return m_particles; }
  std::int64_t bondCount() const { return m_bonds; }
  // How long open()'s Describe took, from the call to its answer (the time a
  // first picture spends on the file's summary).
  double describeMs() const { return m_describeMs; }
  int stepCount() const { return static_cast<int>(m_description->steps.size()); }
  // How the file's writer decided the crack methods divide its bond graph
  // into cells (/index@decomposition); kUnknown when it records none.
  dem::CellDecomposition recordedDecomposition() const;
  const std::vector<StepEntry>& steps() const { return m_description->steps; }

  // The fixed lattice topology, read on first use (alone, or with the first
  // readStep) and kept.
  Result<std::shared_ptr<const std::vector<dem::Bond>>> bonds();
  // The bond list handed over to a caller that keeps it (a step source's
  // lattice): moved when nobody else holds it, else copied. Later steps are
  // read without it, and bonds() is not to be called after.
  Result<std::vector<dem::Bond>> takeBonds();
  bool bondsLoaded() const { return m_bondList != nullptr || m_bondsTaken; }
  // The particles' radii: the prefetched ones (handed over once; this waits
  // for the whole prefetched Read and may return its error), or read now.
  Result<std::vector<double>> radii();

  // Positions and bond states of a step in one Read (with the bond list in
  // the same call when it has not been read yet, and the `extras` the step
  // has; one it lacks stays empty).
  Result<RemoteStep> readStep(int step, StepExtras extras = {});
  // /bonds/break_step: the first step at which each bond broke, -1 if never
  // (as the file has it now: a writer updates it); empty if the file has none.
  Result<std::vector<std::int32_t>> breakSteps() const;
  Result<std::vector<dem::Vec3>> positions(int step) const;
  // Particles [first, first + count) of a step: a spatial block's share.
  Result<std::vector<dem::Vec3>> positions(int step, std::int64_t first, std::int64_t count) const;
  Result<std::vector<std::uint8_t>> bondState(int step) const;
  // The step scalars (load, displacement, ...): one value per step each, NaN
  // where a step has none; in name order. Attributes of the step groups, or
  // an appendable file's /steps/scalars/NAME datasets (one Read).
  struct ScalarSeries {
    std::string name;
    std::vector<double> values;
  };
  Result<std::vector<ScalarSeries>> stepScalars() const;

 private:
  RemoteDemFile() = default;
  Status checkStep(int step) const;
  dem::LayoutSizes sizes() const { return {m_particles, m_bonds}; }
  Result<std::vector<dem::Bond>> toBonds(const TypedArray& array) const;
  Result<std::vector<dem::Vec3>> toPositions(const TypedArray& array, std::uint64_t expected) const;
  Result<std::vector<std::uint8_t>> toBondState(const TypedArray& array) const;
  // Receives the prefetched bond list (and radii, when asked for), if one is
  // on its way; a refused or cut stream leaves them to be read again.
  Status takePrefetchedBonds();
  // The bond list into m_bondList: the prefetched one, or read now.
  Status loadBonds();
  Result<RemoteStep> readStepOnce(int step, StepExtras extras);
  // The slab of step `step` of a per-step dataset whose one step has
  // `rowShape`, and the shape it arrives in: the whole dataset of a step
  // group, or row `step` of an appendable file's dataset ([1, rowShape...]).
  Hyperslab stepSlab(const std::string& path, int step,
                     const std::vector<std::uint64_t>& rowShape) const;
  std::vector<std::uint64_t> stepShape(std::vector<std::uint64_t> rowShape) const;
  // A live file's /steps/writing flag, read into m_beingWritten.
  Status readWritingFlag();

  std::optional<DataClient> m_client;
  std::string m_file;
  std::shared_ptr<const FileDescription> m_description;
  int m_dimension = 0;
  bool m_timeInIterations = false;
  bool m_appendable = false;  // a live file: steps along an extendible axis
  bool m_beingWritten = false;
  double m_describeMs = 0.0;
  std::int64_t m_particles = 0;
  std::int64_t m_bonds = 0;
  std::shared_ptr<std::vector<dem::Bond>> m_bondList;
  bool m_bondsTaken = false;  // takeBonds() gave the list away
  // OpenOptions::prefetchBondList; it makes the file move-only (one reader).
  std::unique_ptr<DataClient::PendingRead> m_prefetchedBonds;
  bool m_radiiAskedFor = false;                          // OpenOptions::prefetchRadii
  std::optional<std::vector<double>> m_prefetchedRadii;  // arrived with the list
};

}  // namespace crackvis::dataservice
