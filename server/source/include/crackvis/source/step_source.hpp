// Where a render session's data comes from: the lattice once, then the
// positions and bond states of one step at a time (with velocities, bond
// forces, break steps only when the view colours by them). RemoteSource reads
// through crackvis-data with partial reads only (the bond list and radii once
// per file, then one Read per step of what it needs); LocalSource
// reads a file beside the process (crackvis-render --snapshot --data-root,
// tests). StepCache keeps recent steps and prefetches the next one on its own
// thread while a session plays.
#pragma once

#include <array>
#include <condition_variable>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/dem/model.hpp>
#include <crackvis/dem/spatial_index.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::source {

// One step as a scene needs it.
struct SourceStep {
  int index = 0;
  double time = 0.0;
  std::vector<dem::Vec3> positions;     // [N]
  std::vector<std::uint8_t> bondState;  // [M]
  // Only what the view colours by (ExtraArrays) and the file has; else empty.
  std::vector<std::array<float, 3>> velocities;  // [N]
  std::vector<float> bondForce;                  // [M]
  // The per-particle extra array the view colours by (crackvis-dem v1.1), one
  // value per particle (a 3-vector's magnitude).
  std::vector<float> particleExtra;  // [N]
  std::vector<float> bondExtra;      // [M] likewise, the bond extra array coloured by
  double loadMs = 0.0;               // time the read took
};

// The arrays beyond positions and bond states that a view colours by: read
// only when it does, so that the usual view moves the least data.
struct ExtraArrays {
  bool velocities = false;    // per step, [N, 3]
  bool bondForce = false;     // per step, [M]
  bool breakStep = false;     // per file, [M]
  std::string particleExtra;  // NAME of extra/particles/NAME (per step or constant); "" none
  std::string bondExtra;      // NAME of extra/bonds/NAME; "" none
  friend bool operator==(const ExtraArrays&, const ExtraArrays&) = default;
};

// A step from the cache: the data and what getting it cost now.
struct CachedStep {
  std::shared_ptr<const SourceStep> step;
  // 0 for a cache hit; for a step whose prefetch was under way, the wait
  // for it (the part of the read nothing else hid).
  double loadMs = 0.0;
};

// Not thread-safe; StepCache serialises its calls.
class StepSource {
 public:
  virtual ~StepSource() = default;
  virtual const std::string& file() const = 0;
  // Radii and bonds (strengths may be empty: a view does not need them).
  virtual const dem::Lattice& lattice() const = 0;
  virtual int stepCount() const = 0;
  // Which extra arrays read() brings from now on; reads the break steps (once)
  // when they are asked for. Called before the source goes into a StepCache.
  virtual Status setExtraArrays(const ExtraArrays& extras) = 0;
  // /bonds/break_step when asked for and the file has it; else empty.
  virtual const std::vector<std::int32_t>& breakSteps() const = 0;
  // OUT_OF_RANGE naming the file's steps for a step outside them.
  virtual Result<SourceStep> read(int step) = 0;
  // Whether steps' times are the code's step numbers (the file's
  // time_unit is "iteration": the code wrote no time).
  virtual bool timeInIterations() const { return false; }
  // A live file (crackvis-dem v1.2's appendable layout): one that may grow.
  virtual bool appendable() const { return false; }
  // A live file whose writer had it open when last looked at.
  virtual bool beingWritten() const { return false; }
  // Looks at the file again: true when it has more steps now (the break
  // steps, when asked for, are read again). FAILED_PRECONDITION when the
  // file was replaced by another. A file that cannot grow answers false.
  virtual Result<bool> refresh() { return false; }
  // How long describing the file took as it was opened: crackvis-data's
  // Describe for a remote file; 0 for a local one (its reader opens it).
  virtual double describeMs() const { return 0.0; }
  // How the file's writer decided the crack methods divide its bond graph
  // into cells (/index@decomposition), which a view's "auto" then takes
  // (cracks::settledByFile); kUnknown when the file records none.
  virtual dem::CellDecomposition recordedDecomposition() const {
    return dem::CellDecomposition::kUnknown;
  }
};

// `file` relative to the data service's root. A file declaring more
// particles or bonds than `limits` is refused (RESOURCE_EXHAUSTED) before
// its arrays are allocated.
Result<std::unique_ptr<StepSource>> openRemoteSource(const dataservice::DataClient& client,
                                                     const std::string& file,
                                                     const dem::SizeLimits& limits = {});
// How a local file is first opened: in this process, or with its structure
// read in a child first (DemFileReader::openGuarded), for the one-shot
// readers (snapshot, movie, crackvis-render --snapshot) that a libhdf5 fault
// on a corrupt file would otherwise kill. Sessions that run beside other
// threads' HDF5 work open in process.
enum class LocalOpen { kInProcess, kStructureInChild };

// `path` on this machine.
Result<std::unique_ptr<StepSource>> openLocalSource(const std::string& path,
                                                    const dem::SizeLimits& limits = {},
                                                    LocalOpen how = LocalOpen::kInProcess);

// OUT_OF_RANGE "FILE: step K out of range (the file has steps 0..N-1)": the
// one step check of every reader.
using dem::checkStepInRange;

class StepCache {
 public:
  StepCache(std::unique_ptr<StepSource> source, std::size_t capacity = 8);
  StepCache(const StepCache&) = delete;
  StepCache& operator=(const StepCache&) = delete;
  ~StepCache();  // stops and joins the prefetch thread

  const StepSource& source() const { return *m_source; }
  // The step from the cache, or read now (a prefetch in progress of the same
  // step is waited for rather than read twice).
  Result<CachedStep> get(int step);
  // Reads `step` in the background unless cached or out of range.
  void prefetch(int step);
  // Reads `step` now without keeping it: a scan over the whole series must
  // not push the steps a session shows out of the cache.
  Result<SourceStep> readAside(int step);
  // StepSource::refresh, between reads (the prefetch thread's included).
  Result<bool> refresh();

  struct Stats {
    std::uint64_t hits = 0;
    std::uint64_t misses = 0;
    std::uint64_t prefetched = 0;
  };
  Stats stats() const;

 private:
  std::shared_ptr<const SourceStep> lookup(int step);   // under m_mutex
  bool cached(int step) const;                          // under m_mutex, order kept
  void insert(std::shared_ptr<const SourceStep> step);  // under m_mutex
  void prefetchLoop();

  std::unique_ptr<StepSource> m_source;
  std::size_t m_capacity;
  mutable std::mutex m_mutex;
  std::condition_variable m_changed;
  std::list<std::shared_ptr<const SourceStep>> m_steps;  // most recent first
  std::mutex m_readMutex;                                // one read at a time
  int m_reading = -1;                                    // step being read, under m_mutex
  int m_wanted = -1;                                     // next prefetch, under m_mutex
  bool m_stopping = false;
  Stats m_stats;
  std::thread m_prefetcher;
};

}  // namespace crackvis::source
