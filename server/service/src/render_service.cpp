#include "render_service.hpp"

#include <algorithm>
#include <atomic>
#include <limits>
#include <map>
#include <mutex>
#include <random>
#include <thread>

#include <fmt/format.h>

#include "client_events.hpp"
#include "crackvis/v1/data.pb.h"
#include "stream_encoder.hpp"
#include <crackvis/common/data_root.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dem/model.hpp>
#include <crackvis/dem_layout/layout.hpp>
#include <crackvis/rpc/grpc_status.hpp>

namespace crackvis::service {

using rpc::AccessRecord;
using rpc::Caller;

namespace {

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
  auto normalized = DataRoot::normalize(file);
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

// Times, broken bonds and step scalars per step (docs/data-format.md: the
// attributes of a step group but its time, or an appendable file's
// /steps/scalars datasets).
Status fillStepHistory(const dataservice::RemoteDemFile& file,
                       const std::vector<std::int32_t>& breaks, v1::StepHistoryResponse& response) {
  const int steps = file.stepCount();
  for (const std::int64_t broken : dem::brokenBondsPerStep(breaks, steps)) {
    response.add_broken_bonds(broken);
  }
  response.set_bond_count(file.bondCount());
  for (const dataservice::StepEntry& entry : file.steps()) {
    response.add_time(entry.time);
  }
  auto scalars = file.stepScalars();
  if (!scalars) {
    return scalars.status();
  }
  for (const auto& series : *scalars) {
    auto* s = response.add_scalars();
    s->set_name(series.name);
    s->mutable_values()->Add(series.values.begin(), series.values.end());
  }
  return Status::ok();
}

void addSeries(const std::vector<analysis::NamedSeries>& series,
               v1::StepHistoryResponse& response) {
  for (const analysis::NamedSeries& one : series) {
    auto* out = response.add_scalars();
    out->set_name(one.name);
    out->mutable_values()->Add(one.values.begin(), one.values.end());
  }
}

// Whether `file` is still the version named `revision`: the numbers of a
// run are kept under a revision only when the file did not change while it
// ran (a Describe answered from crackvis-data's cache: about 2 ms).
bool stillRevision(const dataservice::DataClient& data, const std::string& file,
                   const std::string& revision, dataservice::DataClient::Deadline deadline) {
  v1::DescribeRequest request;
  request.set_file(file);
  v1::DescribeResponse described;
  return data.relayDescribe(request, described, deadline).isOk() &&
         described.revision() == revision;
}

}  // namespace

template <typename Body>
grpc::Status RenderServiceImpl::handle(grpc::ServerContext* context, const char* method,
                                       Body&& body) {
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

grpc::Status RenderServiceImpl::OpenSession(grpc::ServerContext* context,
                                            const v1::OpenSessionRequest* request,
                                            v1::OpenSessionResponse* response) {
  return handle(context, "OpenSession", [&](const Caller& caller, AccessRecord& record) {
    return openSession(caller, *request, *response, record);
  });
}

grpc::Status RenderServiceImpl::Stream(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>* stream) {
  return handle(context, "Stream", [&](const Caller& caller, AccessRecord& record) {
    return runStream(context, stream, caller, record);
  });
}

grpc::Status RenderServiceImpl::Snapshot(grpc::ServerContext* context,
                                         const v1::SnapshotRequest* request,
                                         v1::SnapshotResponse* response) {
  return handle(context, "Snapshot", [&](const Caller& caller, AccessRecord& record) {
    return snapshot(caller, *request, *response, record, context->deadline());
  });
}

grpc::Status RenderServiceImpl::CloseSession(grpc::ServerContext* context,
                                             const v1::CloseSessionRequest* request,
                                             v1::CloseSessionResponse* /*response*/) {
  return handle(context, "CloseSession", [&](const Caller& caller, AccessRecord& /*record*/) {
    return closeSession(caller, *request);
  });
}

grpc::Status RenderServiceImpl::ListFiles(grpc::ServerContext* context,
                                          const v1::ListFilesRequest* request,
                                          v1::ListFilesResponse* response) {
  return handle(context, "ListFiles", [&](const Caller& caller, AccessRecord& record) {
    return listFiles(caller, *request, *response, record, context->deadline());
  });
}

grpc::Status RenderServiceImpl::Describe(grpc::ServerContext* context,
                                         const v1::DescribeRequest* request,
                                         v1::DescribeResponse* response) {
  return handle(context, "Describe", [&](const Caller& caller, AccessRecord& record) {
    return describe(caller, *request, *response, record, context->deadline());
  });
}

grpc::Status RenderServiceImpl::StepHistory(grpc::ServerContext* context,
                                            const v1::StepHistoryRequest* request,
                                            v1::StepHistoryResponse* response) {
  return handle(context, "StepHistory", [&](const Caller& caller, AccessRecord& record) {
    return stepHistory(caller, *request, *response, record, context->deadline());
  });
}

Status RenderServiceImpl::closeSession(const Caller& caller,
                                       const v1::CloseSessionRequest& request) {
  return m_sessions.close(request.session_id(), caller);
}

Status RenderServiceImpl::listFiles(const Caller& caller, const v1::ListFilesRequest& request,
                                    v1::ListFilesResponse& response, AccessRecord& record,
                                    Deadline deadline) {
  record.file = request.folder();
  auto folder = DataRoot::normalize(request.folder());
  if (!folder) {
    return folder.status();
  }
  // Another user's folder answers as a missing one, as crackvis-data's.
  if (!caller.mayList(*folder)) {
    return DataRoot::notFound(*folder, /*folder=*/true);
  }
  v1::ListFilesResponse all;
  CRACKVIS_RETURN_IF_ERROR(m_data.relayListFiles(request, all, deadline));
  // Both the name shown and the file it leads to must be the caller's.
  for (const auto& file : all.files()) {
    if (!file.resolved_path().empty() &&
        rpc::checkResolvedPath(caller, file.path(), file.resolved_path()).isOk()) {
      *response.add_files() = file;
    }
  }
  return Status::ok();
}

Status RenderServiceImpl::describe(const Caller& caller, const v1::DescribeRequest& request,
                                   v1::DescribeResponse& response, AccessRecord& record,
                                   Deadline deadline) {
  record.file = request.file();
  CRACKVIS_RETURN_IF_ERROR(checkAccess(m_data, caller, request.file(), deadline));
  return m_data.relayDescribe(request, response, deadline);
}

Status RenderServiceImpl::stepHistory(const Caller& caller, const v1::StepHistoryRequest& request,
                                      v1::StepHistoryResponse& response, AccessRecord& record,
                                      Deadline deadline) {
  record.file = request.file();
  CRACKVIS_RETURN_IF_ERROR(checkAccess(m_data, caller, request.file(), deadline));
  auto file = dataservice::RemoteDemFile::open(m_data, request.file());
  if (!file) {
    return file.status();
  }
  auto breakSteps = file->breakSteps();
  if (!breakSteps) {
    return breakSteps.status();
  }
  CRACKVIS_RETURN_IF_ERROR(fillStepHistory(*file, *breakSteps, response));
  record.bytes = breakSteps->size() * sizeof(std::int32_t);
  if (request.cracks().empty()) {
    return Status::ok();
  }
  return addCracks(caller, request, response, deadline);
}

// The crack's numbers per step: the method over the whole file, one such
// call per user at a time.
Status RenderServiceImpl::addCracks(const Caller& caller, const v1::StepHistoryRequest& request,
                                    v1::StepHistoryResponse& response, Deadline deadline) {
  auto method = cracks::parseMethod(request.cracks());
  if (!method) {
    return invalidArgument(fmt::format("cracks: {}", method.status().message()));
  }
  CRACKVIS_RETURN_IF_ERROR(m_crackHistories.enter(caller.name));
  struct Leave {
    CrackHistories& gate;
    const std::string& user;
    ~Leave() { gate.leave(user); }
  } leave{m_crackHistories, caller.name};
  // Whether the import kept the modes the code recorded (at the first
  // step's extra arrays, as every step has them).
  v1::DescribeRequest describe;
  describe.set_file(request.file());
  v1::DescribeResponse described;
  CRACKVIS_RETURN_IF_ERROR(m_data.relayDescribe(describe, described, deadline));
  const std::string recorded = fmt::format("/extra/bonds/{}", dem::kBreakModeArray);
  const bool withModes = std::any_of(
      described.datasets().begin(), described.datasets().end(), [&](const auto& dataset) {
        return dataset.path().starts_with("/steps/") && dataset.path().ends_with(recorded);
      });
  // A finished file's series are kept by its revision: no step is run again.
  const std::string finishedKey =
      described.revision().empty()
          ? std::string()
          : FinishedSeries::key(described.revision(), *method, withModes, response.time_size());
  if (!finishedKey.empty()) {
    if (auto kept = m_finishedSeries.find(finishedKey)) {
      addSeries(*kept, response);
      response.set_crack_steps_computed(0);
      return Status::ok();
    }
  }
  // A live file's run goes on from where this user's last call left it.
  auto run = m_crackHistories.take(caller.name, request.file(), *method, withModes);
  if (!run) {
    auto source = source::openRemoteSource(m_data, request.file(), m_config.limits.fileSizes);
    if (!source) {
      return source.status();
    }
    auto started = CrackHistoryRun::start(std::move(source).value(), *method, withModes);
    if (!started) {
      return started.status();
    }
    run = std::move(started).value();
  }
  auto series = run->series(response.time_size(), deadline);
  // A deadline stops it between two steps, so what it analysed holds; after
  // another error the run's state is not trusted.
  const bool whole = series || series.status().code() == StatusCode::kDeadlineExceeded;
  if (whole && run->live()) {
    m_crackHistories.keep(caller.name, std::move(run));
  }
  if (!series) {
    return series.status();
  }
  addSeries(series->series, response);
  response.set_crack_steps_computed(series->computed);
  if (!finishedKey.empty() && run && run->finished() &&
      stillRevision(m_data, request.file(), described.revision(), deadline)) {
    m_finishedSeries.store(finishedKey, std::move(series->series));
  }
  return Status::ok();
}

void RenderServiceImpl::reapCrackHistories() {
  m_crackHistories.dropIdle();
}

Session::SourceOpener RenderServiceImpl::opener(const Caller& caller) const {
  return [data = m_data, caller, sizes = m_config.limits.fileSizes](
             const std::string& file) -> Result<std::unique_ptr<source::StepSource>> {
    // No caller's deadline here: the data client's timeout bounds the call.
    CRACKVIS_RETURN_IF_ERROR(
        checkAccess(data, caller, file, dataservice::DataClient::Deadline::max()));
    return source::openRemoteSource(data, file, sizes);
  };
}

Status RenderServiceImpl::openSession(const Caller& caller, const v1::OpenSessionRequest& request,
                                      v1::OpenSessionResponse& response, AccessRecord& record) {
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
    session = Session::open(newSessionId(), *description, opener(caller), m_config.limits, m_turns,
                            m_renderers, m_trimmer);
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

namespace {

// The gRPC stream as a sink: Write blocks until gRPC has taken the message.
class GrpcSink final : public StreamSink {
 public:
  GrpcSink(grpc::ServerContext& context,
           grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>& stream,
           const std::atomic<bool>& readerDone)
      : m_context(context), m_stream(stream), m_readerDone(readerDone) {}
  bool write(const v1::ServerMessage& message) override { return m_stream.Write(message); }
  bool open() const override { return !m_readerDone && !m_context.IsCancelled(); }

 private:
  grpc::ServerContext& m_context;
  grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>& m_stream;
  const std::atomic<bool>& m_readerDone;
};

}  // namespace

Result<std::shared_ptr<Session>> RenderServiceImpl::attachStream(const Caller& caller,
                                                                 const v1::ClientEvent& first,
                                                                 AccessRecord& record) {
  if (first.event_case() != v1::ClientEvent::kAttachSessionId) {
    return invalidArgument(
        "the first message of a stream attaches to a session (attach_session_id)");
  }
  auto found = m_sessions.find(first.attach_session_id(), caller);
  if (found) {
    record.file = (*found)->info().file;
  }
  return found;
}

void RenderServiceImpl::applyEvent(Session& session, const v1::ClientEvent& event) const {
  auto converted = toSessionEvent(event);
  Status valid = converted.status();
  if (converted) {
    valid = checkEvent(*converted, m_config.limits);  // before it is queued
  }
  if (valid) {
    session.post(std::move(converted).value());
  } else {
    session.reportEventError(event.event_id(), valid);
  }
}

Status RenderServiceImpl::runStream(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>* stream, const Caller& caller,
    AccessRecord& record) {
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
  auto found = attachStream(caller, first, record);
  if (!found) {
    return found.status();
  }
  std::shared_ptr<Session> session = std::move(found).value();
  const std::uint64_t attachment = session->attach();
  std::atomic<bool> readerDone{false};
  std::thread reader([&] {
    // This thread's boundary: an exception ends the stream, not the process.
    const Status read = rpc::guarded(kProgram, record, [&] {
      v1::ClientEvent event;
      while (stream->Read(&event)) {
        applyEvent(*session, event);
      }
      return Status::ok();
    });
    if (!read) {
      context->TryCancel();
    }
    readerDone = true;
  });
  GrpcSink sink(*context, *stream, readerDone);
  const Status ended = pumpStream(*session, attachment, sink, record);
  session->detach(attachment);
  if (!readerDone) {
    context->TryCancel();  // ends the reader's blocking Read
  }
  reader.join();
  return ended;
}

Status RenderServiceImpl::pumpStream(Session& session, std::uint64_t attachment, StreamSink& sink,
                                     AccessRecord& record) {
  StreamEncoder encoder;
  Status ended = Status::ok();
  bool open = true;
  while (open && sink.open()) {
    RenderedFrame frame;
    SessionNotice notice;
    v1::ServerMessage message;
    switch (session.next(attachment, std::chrono::milliseconds(100), frame, notice)) {
      case Session::Next::kFrame: {
        auto encoded = encoder.encode(frame);
        if (!encoded) {
          ended = encoded.status();
          open = false;
          continue;
        }
        record.bytes += encoded->h264().size();
        *message.mutable_frame() = std::move(encoded).value();
        open = sink.write(message);
        break;
      }
      case Session::Next::kNotice:
        open = sink.write(toMessage(notice));
        break;
      case Session::Next::kTimeout:
        break;
      case Session::Next::kSuperseded:
        ended = unavailable(fmt::format("session {}: another stream attached", session.id()));
        open = false;
        continue;
      case Session::Next::kClosed: {
        const std::string reason = session.closeReason();
        ended = unavailable(
            fmt::format("session {} closed{}", session.id(), reason.empty() ? "" : ": " + reason));
        open = false;
        continue;
      }
    }
    if (auto stats = encoder.stats(session.framesDropped())) {
      v1::ServerMessage statsMessage;
      *statsMessage.mutable_stats() = *stats;
      open = open && sink.write(statsMessage);
    }
  }
  return ended;
}

Status RenderServiceImpl::snapshot(const Caller& caller, const v1::SnapshotRequest& request,
                                   v1::SnapshotResponse& response, AccessRecord& record,
                                   Deadline deadline) {
  auto session = m_sessions.find(request.session_id(), caller);
  if (!session) {
    return session.status();
  }
  record.file = (*session)->info().file;
  // Checked again: a link may have been changed since the session opened.
  CRACKVIS_RETURN_IF_ERROR(checkAccess(m_data, caller, record.file, deadline));
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

}  // namespace crackvis::service
