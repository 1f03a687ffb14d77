// The RenderService over gRPC (synchronous API: a stream's writer loop and
// its reader thread each block on their own side of the call, so a slow
// client holds up neither the session's rendering nor other calls) and the
// RenderServer that hosts it.
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <map>
#include <random>

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include "client_events.hpp"
#include "crackvis/v1/data.pb.h"
#include "crackvis/v1/render.grpc.pb.h"
#include <crackvis/common/log.hpp>
#include <crackvis/dataservice/data_root.hpp>
#include <crackvis/dataservice/remote_dem_file.hpp>
#include <crackvis/dem/layout.hpp>
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/rpc/access_log.hpp>
#include <crackvis/rpc/call.hpp>
#include <crackvis/rpc/credentials.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/rpc/server.hpp>
#include <crackvis/service/render_server.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::service {
namespace {

namespace v1 = crackvis::v1;
using rpc::AccessRecord;
using rpc::Caller;
using rpc::toGrpcStatus;

constexpr const char* kProgram = "crackvis-render";

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string newSessionId() {
  static std::mutex mutex;
  static std::mt19937_64 generator{std::random_device{}()};
  std::lock_guard lock(mutex);
  return fmt::format("{:016x}{:016x}", generator(), generator());
}

// The caller's folder rule on the file as named and, asking crackvis-data
// where it leads, on the real file (rpc::checkResolvedPath, the rule
// crackvis-data applies to its own users): a symlink in the caller's folder
// cannot lend another user's file.
Status checkAccess(const dataservice::DataClient& data, const Caller& caller,
                   const std::string& file, dataservice::DataClient::Deadline deadline) {
  auto normalized = dataservice::DataRoot::normalize(file);
  if (!normalized) {
    return normalized.status();
  }
  CRACKVIS_RETURN_IF_ERROR(rpc::checkNamedPath(caller, *normalized));
  auto resolved = data.resolve(*normalized, deadline);
  if (!resolved) {
    return resolved.status();
  }
  return rpc::checkResolvedPath(caller, *normalized, *resolved);
}

// Streams that have not sent their first (attaching) message yet. Each holds
// one of gRPC's handler threads while it waits, so one past its time is
// cancelled by the reaper: 500 streams that never attach cannot pin 500
// threads for ever.
class AttachWatch {
 public:
  explicit AttachWatch(double seconds) : m_seconds(seconds) {}

  std::uint64_t add(grpc::ServerContext* context) {
    std::lock_guard lock(m_mutex);
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(m_seconds));
    m_waiting.emplace(++m_next, Waiting{context, deadline});
    return m_next;
  }
  // Called before the handler returns, so the reaper never sees a context
  // that has gone. False when the reaper had cancelled the stream.
  bool remove(std::uint64_t id) {
    std::lock_guard lock(m_mutex);
    return m_waiting.erase(id) == 1;
  }
  void cancelOverdue() {
    std::lock_guard lock(m_mutex);
    const auto now = Clock::now();
    for (auto it = m_waiting.begin(); it != m_waiting.end();) {
      if (now > it->second.deadline) {
        it->second.context->TryCancel();
        it = m_waiting.erase(it);
      } else {
        ++it;
      }
    }
  }
  double seconds() const { return m_seconds; }

 private:
  struct Waiting {
    grpc::ServerContext* context;
    Clock::time_point deadline;
  };
  const double m_seconds;
  std::mutex m_mutex;
  std::map<std::uint64_t, Waiting> m_waiting;
  std::uint64_t m_next = 0;
};

// The sessions of a server, with their owners; closes those whose stream
// has been gone longer than the grace period.
class SessionRegistry {
 public:
  SessionRegistry(int limit, int perUserLimit, double graceSeconds)
      : m_limit(limit), m_perUserLimit(perUserLimit), m_grace(graceSeconds) {}

  // `perUser`: the owner is a configured user, counted against the
  // per-user limit (without users every client of one certificate name is
  // one owner). A full server lets in an owner below its fair share (the
  // limit divided among the owners with sessions, the newcomer counted) by
  // reclaiming a session of the owner furthest above it: the one whose
  // stream has been gone longest, else the one idle longest. It goes in
  // `reclaimed`, for the caller to close outside the lock.
  Status reserve(const std::string& owner, bool perUser, std::shared_ptr<Session>& reclaimed) {
    std::lock_guard lock(m_mutex);
    std::map<std::string, int> held = m_openingBy;
    for (const auto& [id, entry] : m_sessions) {
      ++held[entry.owner];
    }
    const int own = held[owner];
    if (perUser && own >= m_perUserLimit) {
      return resourceExhausted(fmt::format("user '{}' has the maximum of {} sessions per user open",
                                           owner, m_perUserLimit));
    }
    if (static_cast<int>(m_sessions.size()) + m_opening >= m_limit) {
      const int share = std::max(1, m_limit / static_cast<int>(held.size()));
      auto victim = own < share ? reclaimable(held, share) : m_sessions.end();
      if (victim == m_sessions.end()) {
        return resourceExhausted(fmt::format(
            "the server has its maximum of {} sessions open ({} owners; a fair share is {}, "
            "and '{}' holds {})",
            m_limit, held.size(), share, owner, own));
      }
      reclaimed = std::move(victim->second.session);
      m_sessions.erase(victim);
    }
    ++m_opening;
    ++m_openingBy[owner];
    return Status::ok();
  }
  void add(std::shared_ptr<Session> session, std::string owner) {
    std::lock_guard lock(m_mutex);
    --m_opening;
    if (--m_openingBy[owner] <= 0) {
      m_openingBy.erase(owner);
    }
    if (session) {
      const std::string id = session->id();
      m_sessions[id] = {std::move(session), std::move(owner)};
    }
  }

  Result<std::shared_ptr<Session>> find(const std::string& id, const Caller& caller) const {
    std::lock_guard lock(m_mutex);
    auto it = m_sessions.find(id);
    if (it == m_sessions.end()) {
      return notFound(fmt::format("no session '{}' (closed, expired or never opened)", echoed(id)));
    }
    if (it->second.owner != caller.name) {
      return permissionDenied(
          fmt::format("session '{}' belongs to another user than '{}'", echoed(id), caller.name));
    }
    return it->second.session;
  }

  Status close(const std::string& id, const Caller& caller) {
    auto session = find(id, caller);
    if (!session) {
      return session.status();
    }
    (*session)->close();
    std::shared_ptr<Session> last;
    {
      std::lock_guard lock(m_mutex);
      auto it = m_sessions.find(id);
      if (it != m_sessions.end()) {
        last = std::move(it->second.session);
        m_sessions.erase(it);
      }
    }
    return Status::ok();  // `last` joins the session's thread here, outside the lock
  }

  // Closes sessions whose stream has been gone longer than the grace.
  void reap() {
    std::vector<std::shared_ptr<Session>> expired;
    {
      std::lock_guard lock(m_mutex);
      const auto now = Clock::now();
      for (auto it = m_sessions.begin(); it != m_sessions.end();) {
        auto since = it->second.session->detachedSince();
        if (it->second.session->closed() ||
            (since && std::chrono::duration<double>(now - *since).count() > m_grace)) {
          it->second.session->close();
          expired.push_back(std::move(it->second.session));
          it = m_sessions.erase(it);
        } else {
          ++it;
        }
      }
    }
    for (auto& session : expired) {
      log::event(
          stderr, "crackvis-render", "session_expired",
          {{"session", session->id()}, {"no_stream_seconds", fmt::format("{:.1f}", m_grace)}});
    }
  }

  void closeAll() {
    std::map<std::string, Entry> all;
    {
      std::lock_guard lock(m_mutex);
      all.swap(m_sessions);
    }
    for (auto& [id, entry] : all) {
      entry.session->close();
    }
  }

  int count() const {
    std::lock_guard lock(m_mutex);
    return static_cast<int>(m_sessions.size());
  }

 private:
  struct Entry {
    std::shared_ptr<Session> session;
    std::string owner;
  };
  using Entries = std::map<std::string, Entry>;

  // The session to reclaim from the owner furthest above `share` (none when
  // every owner is within it): detached the longest, else idle the longest.
  Entries::iterator reclaimable(const std::map<std::string, int>& held, int share) {
    std::string richest;
    int most = share;
    for (const auto& [owner, count] : held) {
      if (count > most) {
        richest = owner;
        most = count;
      }
    }
    auto victim = m_sessions.end();
    auto rank = [](const Session& session) {
      const auto detached = session.detachedSince();
      // A session without a stream goes before any with one.
      return std::pair{detached ? 0 : 1, detached ? *detached : session.lastActive()};
    };
    for (auto it = m_sessions.begin(); it != m_sessions.end() && !richest.empty(); ++it) {
      if (it->second.owner == richest &&
          (victim == m_sessions.end() ||
           rank(*it->second.session) < rank(*victim->second.session))) {
        victim = it;
      }
    }
    return victim;
  }

  const int m_limit;
  const int m_perUserLimit;
  const double m_grace;
  mutable std::mutex m_mutex;
  std::map<std::string, Entry> m_sessions;
  int m_opening = 0;
  std::map<std::string, int> m_openingBy;
};

// Encodes a stream's frames and keeps its per-second statistics. One per
// stream: a new stream starts a new encoder, so its first frame is a keyframe.
class StreamEncoder {
 public:
  Result<v1::Frame> encode(RenderedFrame& frame) {
    const auto& image = frame.image;
    if (!m_encoder || m_encoder->settings().width != image.width ||
        m_encoder->settings().height != image.height ||
        m_encoder->settings().bitrate != frame.bitrate) {
      auto created = encode::FrameEncoder::create(
          {image.width, image.height, std::max(1, frame.fps), frame.bitrate});
      if (!created) {
        return created.status();
      }
      m_encoder = std::move(created).value();
      frame.keyframe = true;
    }
    const auto start = Clock::now();
    encode::RgbFrame rgb{image.width, image.height, std::move(frame.image.rgb)};
    auto encoded = m_encoder->encode(rgb, frame.keyframe);
    if (!encoded) {
      return encoded.status();
    }
    const double encodeMs = secondsSince(start) * 1000.0;
    v1::Frame out;
    out.set_frame_id(frame.frameId);
    out.set_last_event_id(frame.lastEventId);
    out.set_width(image.width);
    out.set_height(image.height);
    out.set_keyframe(encoded->keyframe);
    out.set_full_resolution(frame.fullResolution);
    out.set_reduction(frame.reduction);
    out.set_particles(frame.particles);
    out.set_step(frame.step);
    out.set_h264(encoded->data.data(), encoded->data.size());
    auto* timings = out.mutable_timings();
    timings->set_load_ms(frame.timings.loadMs);
    timings->set_extract_ms(frame.timings.extractMs);
    timings->set_scene_ms(frame.timings.sceneMs);
    timings->set_render_ms(frame.timings.renderMs);
    timings->set_encode_ms(encodeMs);
    if (frame.lastEventReceived) {
      timings->set_event_to_send_ms(secondsSince(*frame.lastEventReceived) * 1000.0);
    }
    m_window.frames += 1;
    m_window.bytes += encoded->data.size();
    m_window.renderMs += frame.timings.renderMs;
    m_window.encodeMs += encodeMs;
    return out;
  }

  // A stats message once a second.
  std::optional<v1::StreamStats> stats(std::uint64_t dropped) {
    const double seconds = secondsSince(m_windowStart);
    if (seconds < 1.0) {
      return std::nullopt;
    }
    v1::StreamStats out;
    out.set_fps(m_window.frames / seconds);
    out.set_bitrate_bps(8.0 * static_cast<double>(m_window.bytes) / seconds);
    out.set_frames_dropped(dropped);
    if (m_window.frames > 0) {
      out.set_render_ms_mean(m_window.renderMs / m_window.frames);
      out.set_encode_ms_mean(m_window.encodeMs / m_window.frames);
    }
    m_window = {};
    m_windowStart = Clock::now();
    return out;
  }

 private:
  struct Window {
    double frames = 0;
    std::uint64_t bytes = 0;
    double renderMs = 0;
    double encodeMs = 0;
  };
  std::unique_ptr<encode::FrameEncoder> m_encoder;
  Window m_window;
  Clock::time_point m_windowStart = Clock::now();
};

v1::ServerMessage toMessage(const SessionNotice& notice) {
  v1::ServerMessage message;
  if (!notice.error.isOk()) {
    auto* error = message.mutable_error();
    error->set_event_id(notice.eventId);
    error->set_code(static_cast<int>(toGrpcStatus(notice.error).error_code()));
    error->set_message(notice.error.message());
    return message;
  }
  if (notice.pick) {
    const scene::PickResult& picked = *notice.pick;
    auto* pick = message.mutable_pick();
    pick->set_event_id(notice.eventId);
    pick->set_kind(scene::pickedKindName(picked.kind));
    pick->set_index(picked.index);
    pick->set_x(picked.point.x);
    pick->set_y(picked.point.y);
    pick->set_z(picked.point.z);
    for (const scene::PickedValue& v : picked.values) {
      auto* value = pick->add_values();
      value->set_name(v.name);
      value->set_value(v.value);
      value->set_unit(v.unit);
    }
    pick->set_text(scene::describePick(picked));
    return message;
  }
  if (notice.state) {
    auto* state = message.mutable_state();
    state->set_step(notice.state->step);
    state->set_step_count(notice.state->stepCount);
    state->set_playing(notice.state->playing);
    state->set_width(notice.state->width);
    state->set_height(notice.state->height);
    state->set_pipeline_xml(notice.state->pipelineXml);
    state->set_mapped_fraction(notice.state->mappedFraction);
    state->set_crack_warning(notice.state->crackWarning);
  }
  return message;
}

// Times, broken bonds and step scalars per step: every attribute of a step
// group but its time is a named scalar (docs/data-format.md).
void stepHistory(const dataservice::RemoteDemFile& file, const std::vector<std::int32_t>& breaks,
                 v1::StepHistoryResponse& response) {
  const int steps = file.stepCount();
  for (const std::int64_t broken : dem::brokenBondsPerStep(breaks, steps)) {
    response.add_broken_bonds(broken);
  }
  response.set_bond_count(file.bondCount());
  std::map<std::string, int> series;  // name -> index in response.scalars
  for (int k = 0; k < steps; ++k) {
    const dataservice::StepEntry& entry = file.steps()[static_cast<std::size_t>(k)];
    response.add_time(entry.time);
    const dataservice::GroupInfo* group = file.description().findGroup(entry.group);
    if (group == nullptr) {
      continue;
    }
    for (const dataservice::AttributeInfo& attribute : group->attributes) {
      const auto value = group->floatAttribute(attribute.name);
      if (attribute.name == "time" || !value) {
        continue;
      }
      auto [at, added] = series.try_emplace(attribute.name, response.scalars_size());
      if (added) {
        auto* s = response.add_scalars();
        s->set_name(attribute.name);
        s->mutable_values()->Resize(steps, std::numeric_limits<double>::quiet_NaN());
      }
      response.mutable_scalars(at->second)->set_values(k, *value);
    }
  }
}

class RenderServiceImpl final : public v1::RenderService::Service {
 public:
  // `data`: the one channel to crackvis-data, for the handlers and (copied
  // into each opener) the sessions' step sources.
  RenderServiceImpl(const RenderServerConfig& config, dataservice::DataClient data,
                    rpc::AccessLog& log)
      : m_config(config),
        m_authenticator(config.users),
        m_data(std::move(data)),
        m_log(log),
        m_sessions(config.maxSessions, config.maxSessionsPerUser, config.sessionGraceSeconds),
        m_attaching(config.attachSeconds) {}

  SessionRegistry& sessions() { return m_sessions; }
  AttachWatch& attaching() { return m_attaching; }

  grpc::Status OpenSession(grpc::ServerContext* context, const v1::OpenSessionRequest* request,
                           v1::OpenSessionResponse* response) override {
    return handle(context, "OpenSession", [&](const Caller& caller, AccessRecord& record) {
      return openSession(*context, caller, *request, *response, record);
    });
  }

  grpc::Status Stream(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>* stream) override {
    return handle(context, "Stream", [&](const Caller& caller, AccessRecord& record) {
      return runStream(context, stream, caller, record);
    });
  }

  grpc::Status Snapshot(grpc::ServerContext* context, const v1::SnapshotRequest* request,
                        v1::SnapshotResponse* response) override {
    return handle(context, "Snapshot", [&](const Caller& caller, AccessRecord& record) {
      return snapshot(*context, caller, *request, *response, record);
    });
  }

  grpc::Status CloseSession(grpc::ServerContext* context, const v1::CloseSessionRequest* request,
                            v1::CloseSessionResponse* /*response*/) override {
    return handle(context, "CloseSession", [&](const Caller& caller, AccessRecord& /*record*/) {
      return m_sessions.close(request->session_id(), caller);
    });
  }

  grpc::Status ListFiles(grpc::ServerContext* context, const v1::ListFilesRequest* request,
                         v1::ListFilesResponse* response) override {
    return handle(context, "ListFiles", [&](const Caller& caller, AccessRecord& record) {
      record.file = request->folder();
      auto folder = dataservice::DataRoot::normalize(request->folder());
      if (!folder) {
        return folder.status();
      }
      // Another user's folder answers as a missing one, as crackvis-data's.
      if (!caller.mayList(*folder)) {
        return dataservice::DataRoot::notFound(*folder, /*folder=*/true);
      }
      v1::ListFilesResponse all;
      CRACKVIS_RETURN_IF_ERROR(m_data.relayListFiles(*request, all, context->deadline()));
      // Both the name shown and the file it leads to must be the caller's.
      for (const auto& file : all.files()) {
        if (!file.resolved_path().empty() &&
            rpc::checkResolvedPath(caller, file.path(), file.resolved_path()).isOk()) {
          *response->add_files() = file;
        }
      }
      return Status::ok();
    });
  }

  grpc::Status Describe(grpc::ServerContext* context, const v1::DescribeRequest* request,
                        v1::DescribeResponse* response) override {
    return handle(context, "Describe", [&](const Caller& caller, AccessRecord& record) {
      record.file = request->file();
      CRACKVIS_RETURN_IF_ERROR(checkAccess(m_data, caller, request->file(), context->deadline()));
      return m_data.relayDescribe(*request, *response, context->deadline());
    });
  }

  grpc::Status StepHistory(grpc::ServerContext* context, const v1::StepHistoryRequest* request,
                           v1::StepHistoryResponse* response) override {
    return handle(context, "StepHistory", [&](const Caller& caller, AccessRecord& record) {
      record.file = request->file();
      CRACKVIS_RETURN_IF_ERROR(checkAccess(m_data, caller, request->file(), context->deadline()));
      auto file = dataservice::RemoteDemFile::open(m_data, request->file());
      if (!file) {
        return file.status();
      }
      auto breakSteps = file->breakSteps();
      if (!breakSteps) {
        return breakSteps.status();
      }
      stepHistory(*file, *breakSteps, *response);
      record.bytes = breakSteps->size() * sizeof(std::int32_t);
      return Status::ok();
    });
  }

 private:
  // Every handler: authenticate, run the body at the handler boundary (an
  // exception fails only this call), write the access-log line, answer.
  template <typename Body>
  grpc::Status handle(grpc::ServerContext* context, const char* method, Body&& body) {
    const auto start = rpc::CallClock::now();
    AccessRecord record;
    record.method = method;
    const Status status = rpc::guarded(kProgram, record, [&]() -> Status {
      auto caller = rpc::authenticateCall(m_authenticator, *context, record);
      if (!caller) {
        return caller.status();
      }
      return body(*caller, record);
    });
    return rpc::finishCall(m_log, record, start, status);
  }

  Session::SourceOpener opener(const Caller& caller) const {
    return [data = m_data, caller, sizes = m_config.limits.fileSizes](
               const std::string& file) -> Result<std::unique_ptr<source::StepSource>> {
      // No caller's deadline here: the data client's timeout bounds the call.
      CRACKVIS_RETURN_IF_ERROR(
          checkAccess(data, caller, file, dataservice::DataClient::Deadline::max()));
      return source::openRemoteSource(data, file, sizes);
    };
  }

  Status openSession(const grpc::ServerContext& /*context*/, const Caller& caller,
                     const v1::OpenSessionRequest& request, v1::OpenSessionResponse& response,
                     AccessRecord& record) {
    if (request.pipeline_xml().size() > pipeline::kMaxPipelineBytes) {
      return invalidArgument(
          fmt::format("the pipeline is over {} bytes", pipeline::kMaxPipelineBytes));
    }
    auto description = pipeline::parsePipeline(request.pipeline_xml());
    if (!description) {
      return description.status();
    }
    record.file = description->file;
    std::shared_ptr<Session> reclaimed;
    CRACKVIS_RETURN_IF_ERROR(m_sessions.reserve(caller.name, caller.restricted, reclaimed));
    if (reclaimed) {
      reclaimed->close(fmt::format(
          "reclaimed for another user: the server's {} sessions are shared fairly between users",
          m_config.maxSessions));
      log::event(stderr, kProgram, "session_reclaimed",
                 {{"session", reclaimed->id()}, {"for", caller.name}});
      reclaimed.reset();  // joins its thread
    }
    Result<std::shared_ptr<Session>> session = internalError("the session did not open");
    try {
      session = Session::open(newSessionId(), *description, opener(caller), m_config.limits);
    } catch (...) {
      m_sessions.add(nullptr, caller.name);  // the reservation is given back, then rethrown
      throw;
    }
    m_sessions.add(session ? *session : nullptr, caller.name);
    if (!session) {
      return session.status();
    }
    const SessionInfo& info = (*session)->info();
    response.set_session_id((*session)->id());
    response.set_step_count(info.stepCount);
    response.set_particle_count(info.particleCount);
    response.set_bond_count(info.bondCount);
    response.set_backend(info.backend);
    return Status::ok();
  }

  Status runStream(grpc::ServerContext* context,
                   grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>* stream,
                   const Caller& caller, AccessRecord& record) {
    v1::ClientEvent first;
    const std::uint64_t watched = m_attaching.add(context);
    const bool attached = stream->Read(&first);
    const bool timedOut = !m_attaching.remove(watched);
    if (!attached) {
      return timedOut ? deadlineExceeded(fmt::format(
                            "the stream sent no attach_session_id within {} s (attach_seconds)",
                            m_attaching.seconds()))
                      : unavailable("the stream ended before attaching to a session");
    }
    if (first.event_case() != v1::ClientEvent::kAttachSessionId) {
      return invalidArgument(
          "the first message of a stream attaches to a session (attach_session_id)");
    }
    auto found = m_sessions.find(first.attach_session_id(), caller);
    if (!found) {
      return found.status();
    }
    std::shared_ptr<Session> session = std::move(found).value();
    record.file = session->info().file;
    const std::uint64_t attachment = session->attach();
    std::atomic<bool> readerDone{false};
    std::thread reader([&] {
      // This thread's boundary: an exception ends the stream, not the process.
      const Status read = rpc::guarded(kProgram, record, [&] {
        v1::ClientEvent event;
        while (stream->Read(&event)) {
          auto converted = toSessionEvent(event);
          Status valid = converted.status();
          if (converted) {
            valid = checkEvent(*converted, m_config.limits);  // before it is queued
          }
          if (valid) {
            session->post(std::move(converted).value());
          } else {
            session->reportEventError(event.event_id(), valid);
          }
        }
        return Status::ok();
      });
      if (!read) {
        context->TryCancel();
      }
      readerDone = true;
    });
    StreamEncoder encoder;
    Status ended = Status::ok();
    bool open = true;
    while (open && !readerDone && !context->IsCancelled()) {
      RenderedFrame frame;
      SessionNotice notice;
      v1::ServerMessage message;
      switch (session->next(attachment, std::chrono::milliseconds(100), frame, notice)) {
        case Session::Next::kFrame: {
          auto encoded = encoder.encode(frame);
          if (!encoded) {
            ended = encoded.status();
            open = false;
            continue;
          }
          record.bytes += encoded->h264().size();
          *message.mutable_frame() = std::move(encoded).value();
          open = stream->Write(message);
          break;
        }
        case Session::Next::kNotice:
          open = stream->Write(toMessage(notice));
          break;
        case Session::Next::kTimeout:
          break;
        case Session::Next::kSuperseded:
          ended = unavailable(fmt::format("session {}: another stream attached", session->id()));
          open = false;
          continue;
        case Session::Next::kClosed: {
          const std::string reason = session->closeReason();
          ended = unavailable(fmt::format("session {} closed{}", session->id(),
                                          reason.empty() ? "" : ": " + reason));
          open = false;
          continue;
        }
      }
      if (auto stats = encoder.stats(session->framesDropped())) {
        v1::ServerMessage statsMessage;
        *statsMessage.mutable_stats() = *stats;
        open = open && stream->Write(statsMessage);
      }
    }
    session->detach(attachment);
    if (!readerDone) {
      context->TryCancel();  // ends the reader's blocking Read
    }
    reader.join();
    return ended;
  }

  Status snapshot(const grpc::ServerContext& context, const Caller& caller,
                  const v1::SnapshotRequest& request, v1::SnapshotResponse& response,
                  AccessRecord& record) {
    auto session = m_sessions.find(request.session_id(), caller);
    if (!session) {
      return session.status();
    }
    record.file = (*session)->info().file;
    // Checked again: a link may have been changed since the session opened.
    CRACKVIS_RETURN_IF_ERROR(checkAccess(m_data, caller, record.file, context.deadline()));
    int step = 0;
    const std::optional<int> atStep =
        request.has_step() ? std::optional<int>(request.step()) : std::nullopt;
    auto image = (*session)->snapshot(request.width(), request.height(), &step, atStep);
    if (!image) {
      return image.status();
    }
    auto png = render::encodePng(*image);
    if (!png) {
      return png.status();
    }
    record.bytes = png->size();
    response.set_png(png->data(), png->size());
    response.set_width(image->width);
    response.set_height(image->height);
    response.set_step(step);
    return Status::ok();
  }

  const RenderServerConfig& m_config;
  rpc::Authenticator m_authenticator;
  dataservice::DataClient m_data;
  rpc::AccessLog& m_log;
  SessionRegistry m_sessions;
  AttachWatch m_attaching;
};

}  // namespace

dataservice::ClientOptions defaultDataOptions() {
  dataservice::ClientOptions options;
  options.target = "localhost:50051";
  options.tls = tls::defaultTlsFiles("crackvis-render", "--data-", "data_service.");
  return options;
}

struct RenderServer::Impl {
  RenderServerConfig config;
  std::unique_ptr<rpc::AccessLog> log;
  std::unique_ptr<RenderServiceImpl> service;
  std::unique_ptr<rpc::ServerHost> host;  // last: stops before the service goes
};

RenderServer::RenderServer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}

RenderServer::~RenderServer() {
  shutdown(0.5);
}

Result<std::unique_ptr<RenderServer>> RenderServer::start(const RenderServerConfig& config) {
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  auto listener = rpc::prepareListener(config.listen, config.insecure, config.tls);
  if (!listener) {
    return listener.status();
  }
  if (config.data.insecure) {
    // The token would travel in clear: only to this machine.
    CRACKVIS_RETURN_IF_ERROR(rpc::requireLoopback(config.data.target, "--data-insecure"));
  }
  // The same rules as crackvis-render's flags and file: a server started
  // from code (tests, the CLI) cannot bypass them.
  CRACKVIS_RETURN_IF_ERROR(validateRenderServerConfig(config));
  auto data = dataservice::DataClient::connect(impl->config.data);
  if (!data) {
    return Status(data.status().code(),
                  fmt::format("the data service client: {}", data.status().message()));
  }
  auto log = rpc::AccessLog::open(config.accessLog);
  if (!log) {
    return log.status();
  }
  impl->log = std::move(log).value();
  impl->service =
      std::make_unique<RenderServiceImpl>(impl->config, std::move(data).value(), *impl->log);
  RenderServiceImpl* service = impl->service.get();
  rpc::ServerSettings settings;
  settings.program = kProgram;
  settings.service = v1::RenderService::service_full_name();
  settings.maxReceiveMessageBytes = static_cast<int>(pipeline::kMaxPipelineBytes) + 4096;
  settings.reapPeriod = std::chrono::milliseconds(200);
  settings.reap = [service] {
    service->sessions().reap();
    service->attaching().cancelOverdue();
  };
  // Each stream holds a handler thread and a reader thread: cap what many
  // clients opening calls can make us create (gRPC refuses calls beyond it
  // with RESOURCE_EXHAUSTED).
  settings.maxThreads = 4 * config.maxSessions + 32;
  // Closing the sessions ends their streams (next() returns kClosed).
  settings.beforeStop = [service] { service->sessions().closeAll(); };
  auto host = rpc::ServerHost::start(*listener, {service}, std::move(settings));
  if (!host) {
    return host.status();
  }
  impl->host = std::move(host).value();
  return std::unique_ptr<RenderServer>(new RenderServer(std::move(impl)));
}

const std::string& RenderServer::address() const {
  return m_impl->host->address();
}
int RenderServer::port() const {
  return m_impl->host->port();
}
int RenderServer::sessionCount() const {
  return m_impl->service->sessions().count();
}

void RenderServer::shutdown(double graceSeconds) {
  m_impl->host->shutdown(graceSeconds);
}

void RenderServer::wait() {
  m_impl->host->wait();
}

}  // namespace crackvis::service
