// crackvis-hdf5-worker's side of hdf5_workers.hpp: the loop that serves
// the service's requests with a catalogue of its own, and the program's main.
#include <charconv>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string_view>

#include <poll.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include "crackvis/v1/data.pb.h"
#include "describe_proto.hpp"
#include "worker_protocol.hpp"
#include <crackvis/common/child_process.hpp>
#include <crackvis/dataservice_service/hdf5_worker_main.hpp>

namespace crackvis::dataservice {
namespace {

using namespace worker_protocol;

// What a worker may map beyond its start: libhdf5's metadata and chunk
// caches and one decompressed chunk need megabytes; 4 GiB leaves room for
// chunks far larger than any writer we import makes.
constexpr std::uint64_t kLibhdf5Headroom = std::uint64_t{4} << 30;

// What a worker answers to one request: kOk and its payload, or kError and
// an encoded Status.
std::pair<std::uint32_t, std::string> serve(const Catalogue& catalogue, std::uint32_t kind,
                                            std::string_view payload, void* shared) {
  WireReader in(payload);
  const ResolvedPath file = getPath(in);
  auto failed = [](const Status& status) { return std::pair{kError, encodeStatus(status)}; };
  switch (kind) {
    case kDescribe: {
      DescribeOptions options;
      options.limits.maxDepth = static_cast<int>(in.u64());
      options.limits.maxObjects = in.u64();
      options.limits.maxTime = std::chrono::milliseconds(in.u64());
      if (!in.ok()) {
        break;
      }
      auto description = catalogue.describe(file, options);
      if (!description) {
        return failed(description.status());
      }
      crackvis::v1::DescribeResponse response;
      toProto(*description, response);
      return {kOk, response.SerializeAsString()};
    }
    case kPlan: {
      const std::uint64_t count = in.u64();
      if (count > payload.size()) {
        break;
      }
      std::vector<Hyperslab> slabs(count);
      for (Hyperslab& slab : slabs) {
        slab.dataset = in.text();
        slab.start = in.numbers<std::int64_t>();
        slab.count = in.numbers<std::int64_t>();
      }
      const std::uint64_t maxBytes = in.u64();
      if (!in.ok()) {
        break;
      }
      auto reader = catalogue.openRead(file, slabs, maxBytes);
      if (!reader) {
        return failed(reader.status());
      }
      WireWriter out;
      out.u64((*reader)->totalBytes());
      out.u64((*reader)->slabs().size());
      for (const SlabPlan& slab : (*reader)->slabs()) {
        put(out, slab);
      }
      // The first piece comes with the plan, in the shared buffer: one
      // round trip fewer for every Read (a view's has seven). If it cannot
      // be read now, the service asks for it again and gets the error then.
      PieceCursor cursor;
      const auto first = cursor.next((*reader)->slabs());
      const bool read = first && (*reader)->read(*first, shared).isOk();
      out.u64(read ? first->bytes : 0);
      return {kOk, out.take()};
    }
    case kPiece: {
      const SlabPlan slab = getSlab(in);
      const Piece piece = getPiece(in);
      if (!in.ok() || piece.bytes > kMaxChunkBytes) {
        break;
      }
      if (Status read = catalogue.readPiece(file, slab, piece, shared); !read) {
        return failed(read);
      }
      return {kOkShared, {}};
    }
    default:
      break;
  }
  return failed(internalError("an HDF5 worker got a request it cannot read"));
}

[[noreturn]] void runWorker(const DataRoot& root, void* shared) {
  const Catalogue catalogue(root);
  for (;;) {
    pollfd ready{kWorkerSocket, POLLIN, 0};
    const int polled = ::poll(&ready, 1, 1000);
    if (polled == 0) {
      catalogue.closeIdleFiles();  // a writer is not kept out by an idle worker
      continue;
    }
    if (polled < 0) {
      if (errno == EINTR) {
        continue;
      }
      ::_exit(1);
    }
    FrameHeader header;
    const auto forever = Clock::now() + std::chrono::hours(24 * 365);
    if (receiveAll(kWorkerSocket, &header, sizeof header, forever, {}) != Wait::kReady ||
        header.length > (std::uint64_t{64} << 20)) {
      ::_exit(0);  // the service closed the socket (or speaks nonsense): done
    }
    std::string payload(header.length, '\0');
    if (receiveAll(kWorkerSocket, payload.data(), payload.size(), forever, {}) != Wait::kReady) {
      ::_exit(0);
    }
    const auto [kind, answer] = serve(catalogue, header.kind, payload, shared);
    if (!sendFrame(kWorkerSocket, kind, answer)) {
      ::_exit(0);
    }
  }
}

// The first caller's file should not pay for the worker's start: its first
// Describe took about twice a later one's time, and each first touch of a
// page of the piece buffer costs a fault. A failed rehearsal only means the
// first call is slower; that call reports any real problem with libhdf5.
void rehearse(void* shared) {
  if (auto description = rehearseDescribeAndRead()) {
    crackvis::v1::DescribeResponse response;
    toProto(*description, response);
    [[maybe_unused]] const std::string encoded = response.SerializeAsString();
  } else {
    std::fprintf(stderr, "crackvis-hdf5-worker: the rehearsal at start failed: %s\n",
                 description.status().message().c_str());
  }
  std::memset(shared, 0, kMaxChunkBytes);
}

// Whether `fd` is a Unix stream socket: the one a worker is given.
bool isWorkerSocket(int fd) {
  int type = 0;
  socklen_t length = sizeof type;
  return ::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &length) == 0 && type == SOCK_STREAM;
}

// The worker program's arguments: the data root and the service's pid.
std::optional<pid_t> servicePid(std::string_view text) {
  pid_t pid = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), pid);
  if (error != std::errc() || end != text.data() + text.size() || pid <= 1) {
    return std::nullopt;
  }
  return pid;
}

}  // namespace

int hdf5WorkerMain(int argc, char** argv) {
  const std::optional<pid_t> service = argc == 3 ? servicePid(argv[2]) : std::nullopt;
  if (!service || !isWorkerSocket(kWorkerSocket)) {
    std::fprintf(stderr,
                 "crackvis-hdf5-worker: crackvis-data starts this program for its HDF5 work "
                 "(docs/security.md); it is not run by hand\n");
    return 2;
  }
  // Dies with the service's thread that started it; the check after closes
  // the gap in which the service could have died first.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != *service) {
    return 0;
  }
  ::prctl(PR_SET_DUMPABLE, 0);  // no core files of users' data when libhdf5 faults
  // A fault ends the worker by its signal, which the service reports: no
  // handler a sanitizer installed may turn it into an exit status.
  for (const int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) {
    ::signal(signal, SIG_DFL);
  }
  ::signal(SIGPIPE, SIG_IGN);
  void* shared =
      ::mmap(nullptr, kMaxChunkBytes, PROT_READ | PROT_WRITE, MAP_SHARED, kWorkerBuffer, 0);
  ::close(kWorkerBuffer);
  auto root = DataRoot::open(argv[1]);
  if (shared == MAP_FAILED || !root) {
    return 1;  // the service sees the socket close before kReady
  }
  // A corrupt size makes libhdf5 allocate and fill what it says (20 GB for
  // one the fuzzer kept): the worker's allocation fails instead, and its
  // call answers FAILED_PRECONDITION, before the host runs out of memory.
  if (const Status capped = capAddressSpace(kLibhdf5Headroom); !capped) {
    std::fprintf(stderr, "crackvis-hdf5-worker: %s\n", capped.message().c_str());
  }
  rehearse(shared);
  if (!sendFrame(kWorkerSocket, kReady, {})) {
    return 0;
  }
  runWorker(*root, shared);
}

}  // namespace crackvis::dataservice
