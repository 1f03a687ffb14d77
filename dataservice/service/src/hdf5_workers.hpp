// crackvis-data's HDF5 work in supervised worker processes (issue 13.7).
// libhdf5 itself can fault on a corrupt file (a one-bit flip gave a SIGSEGV
// in H5A__close; the fuzzer keeps a heap overflow under H5Aexists), and a
// corrupt file can send it into a loop. Neither can be fixed in crackvis, so
// no HDF5 call runs in the service's own process: Describe, the plan of a
// Read and each of its pieces go to one of a few worker processes, each with
// its own catalogue (and so its own open-file cache). A worker that dies
// fails only the call it was serving, with FAILED_PRECONDITION naming the
// file and the signal, and is replaced at once; one that overruns the
// call's time (or whose caller cancels) is killed and replaced.
//
// A worker is a program of its own (crackvis-hdf5-worker, beside
// crackvis-data), started with posix_spawn: it shares no memory with the
// service but one piece buffer (a memfd), keeps only its socket and that
// buffer, dies with the service (PR_SET_PDEATHSIG) and runs nothing but the
// catalogue. Requests and answers are length-prefixed frames on a Unix
// stream socket; a piece's bytes come back through the shared buffer.
// Private to the service library; hdf5WorkerMain is the program's main.
#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <sys/types.h>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dataservice_h5/data_root.hpp>
#include <crackvis/dataservice_protocol/types.hpp>

namespace crackvis::dataservice {

struct ReadPlan {
  std::vector<SlabPlan> slabs;
  std::uint64_t totalBytes = 0;
  // The first piece (PieceCursor's first), read with the plan; empty when
  // there is none or it could not be read then.
  std::string firstPiece;
};

class Hdf5Workers {
 public:
  struct Settings {
    int workers = 4;
    // A piece read (at most 1 MiB) that takes longer is a worker stuck in
    // libhdf5; Describe gets its own time limit plus this.
    std::chrono::milliseconds pieceTime{30'000};
    // The worker program (crackvis-hdf5-worker) to start.
    std::string program;
  };

  static Result<std::unique_ptr<Hdf5Workers>> start(const DataRoot& root, Settings settings);
  Hdf5Workers(const Hdf5Workers&) = delete;
  Hdf5Workers& operator=(const Hdf5Workers&) = delete;
  ~Hdf5Workers();  // kills and reaps every worker

  // Each call names its `user`: workers are shared fairly between users
  // (issue 29 point 2). A Describe walks a whole file (seconds for a hostile
  // one), so walks may hold all workers but one: a Read's plan and pieces,
  // a few milliseconds each, always find a worker within one piece's time.
  // When callers wait, a free worker goes to the one whose user holds the
  // fewest workers (then the earliest), so one user's many calls do not
  // queue ahead of another user's few.
  //
  // A serialized crackvis.v1.DescribeResponse. `cancelled` is asked every
  // 100 ms while the worker walks the file: true kills the worker.
  Result<std::string> describe(const ResolvedPath& file, const DescribeLimits& limits,
                               const std::function<bool()>& cancelled, const std::string& user);
  // Catalogue::openRead in a worker: the validated plan of every slab.
  Result<ReadPlan> planRead(const ResolvedPath& file, const std::vector<Hyperslab>& slabs,
                            std::uint64_t maxBytes, const std::string& user);
  // Catalogue::readPiece in a worker, into `out` (piece.bytes long).
  Status readPiece(const ResolvedPath& file, const SlabPlan& slab, const Piece& piece, void* out,
                   const std::string& user);

  // For tests and operators: the workers' process ids now, and how many
  // workers have been replaced since start.
  std::vector<pid_t> pids() const;
  int replaced() const;

 private:
  struct Worker {
    pid_t pid = -1;
    int socket = -1;
    void* shared = nullptr;  // kMaxChunkBytes the worker reads pieces into
    bool busy = false;
    // Being replaced: no process now, but one is starting (until it is
    // ready, which takes a moment), so callers wait for it rather than
    // finding no worker at all.
    bool starting = false;
  };
  struct Started {
    pid_t pid;
    int socket;
    void* shared;
  };
  // What a call's answer is written into: a string, or a caller's buffer of
  // a known size (a piece, read straight from the socket).
  struct Answer {
    std::string* text = nullptr;
    void* bytes = nullptr;
    std::uint64_t size = 0;
    // Run on a text answer while the worker is still the call's, with its
    // shared buffer; false: the answer is unreadable.
    std::function<bool(const void* shared)> shared;
  };

  // Walks (Describe) may not take the last free worker; reads may.
  enum class Lane { kWalk, kRead };
  // A caller waiting for a worker.
  struct Ticket {
    std::uint64_t order;
    const std::string* user;
    Lane lane;
  };

  // Starts workers on one thread that lives as long as they do. A worker
  // dies with the *thread* that started it (PR_SET_PDEATHSIG), so a worker
  // started on a caller's thread died as soon as that thread ended (a gRPC
  // thread the pool let go, a Describe's walk thread), and the next call
  // found it dead.
  class SpawnThread {
   public:
    SpawnThread();
    ~SpawnThread();
    // Runs `work` on the thread and waits for it.
    void run(const std::function<void()>& work);

   private:
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::condition_variable m_done;
    const std::function<void()>* m_work = nullptr;
    std::uint64_t m_finished = 0;
    bool m_stop = false;
    std::thread m_thread;
  };

  Hdf5Workers(DataRoot root, Settings settings);
  Status spawn(Worker& worker);
  Result<Started> startWorker();  // maps a buffer and starts a worker
  Result<Started> spawnWorker();  // startWorker's work, on the spawn thread
  Worker* checkOut(Lane lane, const std::string& user);
  void checkIn(Worker* worker, Lane lane, const std::string& user);
  // Whether `ticket` is the waiting caller a free worker goes to next (the
  // lock held).
  bool isNext(const Ticket& ticket) const;
  int walkLimit() const { return std::max(1, static_cast<int>(m_workers.size()) - 1); }
  // Sends a request and waits for its answer; a worker that dies, overruns
  // `deadline` or whose caller cancels is replaced.
  Status call(std::uint32_t kind, Lane lane, const std::string& user, const std::string& request,
              const std::string& file, std::chrono::steady_clock::time_point deadline,
              const std::function<bool()>& isCancelled, Answer answer);
  // Kills (if need be) and reaps a worker, starts another in its place and
  // logs it; returns how the old one ended ("killed by SIGSEGV (signal 11)").
  std::string replace(Worker& worker, const std::string& file, const std::string& why);

  const DataRoot m_root;
  const Settings m_settings;
  const std::string m_environment;  // a worker's one variable, or empty
  mutable std::mutex m_mutex;
  std::condition_variable m_idle;
  std::vector<Worker> m_workers;
  int m_replaced = 0;
  std::unique_ptr<SpawnThread> m_spawns = std::make_unique<SpawnThread>();
  std::vector<const Ticket*> m_waiting;
  std::map<std::string, int> m_held;  // workers each user holds now
  int m_walking = 0;                  // workers on the walk lane now
  std::uint64_t m_tickets = 0;
};

}  // namespace crackvis::dataservice
