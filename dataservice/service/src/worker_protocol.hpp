// What crosses the socket between crackvis-data and an HDF5 worker
// (hdf5_workers.hpp): requests and answers as length-prefixed frames of
// little-endian fields (both sides are the same build). Private to the
// service library.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dataservice_h5/data_root.hpp>

namespace crackvis::dataservice::worker_protocol {

using Clock = std::chrono::steady_clock;

// The two descriptors a worker program is started with: its socket, and the
// memfd of the piece buffer it shares with the service.
constexpr int kWorkerSocket = 3;
constexpr int kWorkerBuffer = 4;

// kOkShared: a piece's bytes are in the worker's shared buffer, not in the
// frame (two copies through the socket cost a view's Read a third more).
// kReady: the worker's first frame, once it has set itself up (its signals,
// the shared buffer, the data root); only then is it given requests.
enum Kind : std::uint32_t {
  kDescribe = 1,
  kPlan = 2,
  kPiece = 3,
  kOk = 100,
  kError = 101,
  kOkShared = 102,
  kReady = 103
};

// ------------------------------------------------------------------ wire --
// Little-endian fields in a string: what crosses the socket between the
// service and a worker (both the same build of the same program).

class WireWriter {
 public:
  void u64(std::uint64_t value) { m_out.append(reinterpret_cast<const char*>(&value), 8); }
  void text(std::string_view value) {
    u64(value.size());
    m_out.append(value);
  }
  template <typename T>
  void numbers(const std::vector<T>& values) {
    u64(values.size());
    for (T value : values) {
      u64(static_cast<std::uint64_t>(value));
    }
  }
  std::string take() { return std::move(m_out); }

 private:
  std::string m_out;
};

class WireReader {
 public:
  explicit WireReader(std::string_view in) : m_in(in) {}
  std::uint64_t u64() {
    std::uint64_t value = 0;
    if (m_in.size() < 8) {
      m_ok = false;
      return 0;
    }
    std::memcpy(&value, m_in.data(), 8);
    m_in.remove_prefix(8);
    return value;
  }
  std::string text() {
    const std::uint64_t size = u64();
    if (size > m_in.size()) {
      m_ok = false;
      return {};
    }
    std::string value(m_in.substr(0, size));
    m_in.remove_prefix(size);
    return value;
  }
  template <typename T>
  std::vector<T> numbers() {
    const std::uint64_t size = u64();
    if (size > m_in.size() / 8) {
      m_ok = false;
      return {};
    }
    std::vector<T> values(size);
    for (T& value : values) {
      value = static_cast<T>(u64());
    }
    return values;
  }
  bool ok() const { return m_ok; }

 private:
  std::string_view m_in;
  bool m_ok = true;
};

void put(WireWriter& out, const ResolvedPath& file);
ResolvedPath getPath(WireReader& in);
void put(WireWriter& out, const SlabPlan& slab);
SlabPlan getSlab(WireReader& in);
void put(WireWriter& out, const Piece& piece);
Piece getPiece(WireReader& in);

std::string encodeStatus(const Status& status);
Status decodeStatus(std::string_view payload);

// ---------------------------------------------------------------- frames --
// A frame: kind (4 bytes), 4 bytes of padding, payload length (8 bytes),
// payload.

struct FrameHeader {
  std::uint32_t kind = 0;
  std::uint32_t padding = 0;
  std::uint64_t length = 0;
};

bool sendAll(int socket, const void* data, std::size_t size);
// One send for the header and the payload: requests and most answers are
// small, and each system call is a wake-up of the other side.
bool sendFrame(int socket, std::uint32_t kind, std::string_view payload);
// Whether an idle worker's socket shows its end closed (it died) or bytes
// nobody asked for; either way it cannot take a request.
bool hungUp(int socket);

enum class Wait { kReady, kClosed, kTimeout, kCancelled };

// Reads exactly `size` bytes, waiting at most until `deadline` and asking
// `cancelled` every 100 ms.
Wait receiveAll(int socket, void* data, std::size_t size, Clock::time_point deadline,
                const std::function<bool()>& cancelled);

}  // namespace crackvis::dataservice::worker_protocol
