#include "worker_protocol.hpp"

#include <algorithm>
#include <cerrno>

#include <poll.h>
#include <sys/socket.h>

namespace crackvis::dataservice::worker_protocol {

void put(WireWriter& out, const ResolvedPath& file) {
  out.text(file.requested);
  out.text(file.relative);
  out.text(file.absolute.string());
}
ResolvedPath getPath(WireReader& in) {
  ResolvedPath file;
  file.requested = in.text();
  file.relative = in.text();
  file.absolute = in.text();
  return file;
}

void put(WireWriter& out, const SlabPlan& slab) {
  out.text(slab.dataset);
  out.text(slab.resolvedDataset);
  out.u64(static_cast<std::uint64_t>(slab.dtype));
  out.numbers(slab.datasetShape);
  out.numbers(slab.start);
  out.numbers(slab.count);
  out.u64(slab.bytes);
  out.u64(slab.rowBytes);
}
SlabPlan getSlab(WireReader& in) {
  SlabPlan slab;
  slab.dataset = in.text();
  slab.resolvedDataset = in.text();
  slab.dtype = static_cast<DataType>(in.u64());
  slab.datasetShape = in.numbers<std::uint64_t>();
  slab.start = in.numbers<std::uint64_t>();
  slab.count = in.numbers<std::uint64_t>();
  slab.bytes = in.u64();
  slab.rowBytes = in.u64();
  return slab;
}

void put(WireWriter& out, const Piece& piece) {
  out.u64(piece.slab);
  out.u64(piece.offset);
  out.u64(piece.bytes);
  out.numbers(piece.start);
  out.numbers(piece.count);
}
Piece getPiece(WireReader& in) {
  Piece piece;
  piece.slab = in.u64();
  piece.offset = in.u64();
  piece.bytes = in.u64();
  piece.start = in.numbers<std::uint64_t>();
  piece.count = in.numbers<std::uint64_t>();
  return piece;
}

std::string encodeStatus(const Status& status) {
  WireWriter out;
  out.u64(static_cast<std::uint64_t>(status.code()));
  out.text(status.message());
  return out.take();
}
Status decodeStatus(std::string_view payload) {
  WireReader in(payload);
  const auto code = static_cast<StatusCode>(in.u64());
  std::string message = in.text();
  if (!in.ok() || code == StatusCode::kOk) {
    return internalError("an HDF5 worker sent an unreadable error");
  }
  return Status(code, std::move(message));
}

bool sendAll(int socket, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t sent = ::send(socket, bytes, size, MSG_NOSIGNAL);
    if (sent < 0) {
      if (errno == EINTR) {
        continue;
      }
      return false;
    }
    bytes += sent;
    size -= static_cast<std::size_t>(sent);
  }
  return true;
}

// One send for the header and the payload: requests and most answers are
// small, and each system call is a wake-up of the other side.
bool sendFrame(int socket, std::uint32_t kind, std::string_view payload) {
  const FrameHeader header{kind, 0, payload.size()};
  std::string frame(reinterpret_cast<const char*>(&header), sizeof header);
  frame.append(payload);
  return sendAll(socket, frame.data(), frame.size());
}

// Whether an idle worker's socket shows its end closed (it died) or bytes
// nobody asked for; either way it cannot take a request.
bool hungUp(int socket) {
  pollfd entry{socket, POLLIN | POLLRDHUP, 0};
  return ::poll(&entry, 1, 0) > 0;
}

// Reads exactly `size` bytes, waiting at most until `deadline` and asking
// `cancelled` every 100 ms.
Wait receiveAll(int socket, void* data, std::size_t size, Clock::time_point deadline,
                const std::function<bool()>& cancelled) {
  auto* bytes = static_cast<char*>(data);
  while (size > 0) {
    // What has arrived already is taken without a poll first.
    const ssize_t got = ::recv(socket, bytes, size, MSG_DONTWAIT);
    if (got > 0) {
      bytes += got;
      size -= static_cast<std::size_t>(got);
      continue;
    }
    if (got == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      return Wait::kClosed;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) {
      return Wait::kTimeout;
    }
    pollfd ready{socket, POLLIN, 0};
    const int polled =
        ::poll(&ready, 1, static_cast<int>(std::min<std::int64_t>(left.count(), 100)));
    if (polled < 0 && errno != EINTR) {
      return Wait::kClosed;
    }
    if (polled <= 0 && cancelled && cancelled()) {
      return Wait::kCancelled;
    }
  }
  return Wait::kReady;
}

}  // namespace crackvis::dataservice::worker_protocol
