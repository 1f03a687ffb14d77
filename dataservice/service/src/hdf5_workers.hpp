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
// Workers are forked from the service while it holds hdf5Mutex(), so no
// HDF5 call of this process is half done in the copy; the child keeps only
// its socket, dies with its parent (PR_SET_PDEATHSIG) and runs nothing but
// the catalogue. Requests and answers are length-prefixed frames on a Unix
// stream socket; a piece's bytes come back through a buffer the two share.
// Private to the service library.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <sys/types.h>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice/catalogue.hpp>
#include <crackvis/dataservice/data_root.hpp>
#include <crackvis/dataservice/types.hpp>

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
  };

  static Result<std::unique_ptr<Hdf5Workers>> start(const DataRoot& root, Settings settings);
  Hdf5Workers(const Hdf5Workers&) = delete;
  Hdf5Workers& operator=(const Hdf5Workers&) = delete;
  ~Hdf5Workers();  // kills and reaps every worker

  // A serialized crackvis.v1.DescribeResponse. `cancelled` is asked every
  // 100 ms while the worker walks the file: true kills the worker.
  Result<std::string> describe(const ResolvedPath& file, const DescribeLimits& limits,
                               const std::function<bool()>& cancelled);
  // Catalogue::openRead in a worker: the validated plan of every slab.
  Result<ReadPlan> planRead(const ResolvedPath& file, const std::vector<Hyperslab>& slabs,
                            std::uint64_t maxBytes);
  // Catalogue::readPiece in a worker, into `out` (piece.bytes long).
  Status readPiece(const ResolvedPath& file, const SlabPlan& slab, const Piece& piece, void* out);

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

  Hdf5Workers(DataRoot root, Settings settings);
  Status spawn(Worker& worker);
  Result<Started> startWorker();  // maps a buffer and forks a worker
  Worker* checkOut();
  void checkIn(Worker* worker);
  // Sends a request and waits for its answer; a worker that dies, overruns
  // `deadline` or whose caller cancels is replaced.
  Status call(std::uint32_t kind, const std::string& request, const std::string& file,
              std::chrono::steady_clock::time_point deadline,
              const std::function<bool()>& isCancelled, Answer answer);
  // Kills (if need be) and reaps a worker, starts another in its place and
  // logs it; returns how the old one ended ("killed by SIGSEGV (signal 11)").
  std::string replace(Worker& worker, const std::string& file, const std::string& why);

  const DataRoot m_root;
  const Settings m_settings;
  mutable std::mutex m_mutex;
  std::condition_variable m_idle;
  std::vector<Worker> m_workers;
  int m_replaced = 0;
};

}  // namespace crackvis::dataservice
