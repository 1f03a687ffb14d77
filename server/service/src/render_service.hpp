// The RenderService over gRPC (synchronous API: a stream's writer loop and
// its reader thread each block on their own side of the call, so a slow
// client holds up neither the session's rendering nor other calls). Each
// handler authenticates the caller, applies its folder rules, and answers
// from crackvis-data or a session; RenderServer (render_server.cpp) hosts
// it. Private to the service library.
#pragma once

#include <algorithm>
#include <cstddef>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "crack_history.hpp"
#include "crackvis/v1/render.grpc.pb.h"
#include "session_registry.hpp"
#include "stream_encoder.hpp"
#include <crackvis/common/heap_reserve.hpp>
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/rpc_server/access_log.hpp>
#include <crackvis/rpc_server/call.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/service/render_server.hpp>
#include <crackvis/service/session.hpp>

namespace crackvis::service {

// The program's name in log lines, the access log and the health service.
inline constexpr const char* kProgram = "crackvis-render";

// Where a session's stream writes its messages: the gRPC stream, or the web
// page's WebSocket. The one writer loop (RenderServiceImpl::pumpStream)
// serves both front doors.
class StreamSink {
 public:
  virtual ~StreamSink() = default;
  // Blocks until the message is handed to the transport (back-pressure: a
  // slow client holds up only its own stream); false when the client is gone.
  virtual bool write(const v1::ServerMessage& message) = 0;
  // False once the client has gone or its events can no longer be read.
  virtual bool open() const = 0;
};

class RenderServiceImpl final : public v1::RenderService::Service {
 public:
  using Deadline = dataservice::DataClient::Deadline;
  // `data`: the one channel to crackvis-data, for the handlers and (copied
  // into each opener) the sessions' step sources.
  RenderServiceImpl(const RenderServerConfig& config, dataservice::DataClient data,
                    rpc::AccessLog& log)
      : m_config(config),
        m_authenticator(config.users),
        m_data(std::move(data)),
        m_log(log),
        m_sessions(config.maxSessions, config.maxSessionsPerUser, config.sessionGraceSeconds),
        m_attaching(config.attachSeconds),
        m_turns(std::make_shared<RenderTurns>(config.limits.rendersAtOnce)),
        m_renderers(config.keptRenderers > 0 ? std::make_shared<RendererShelf>(
                                                   static_cast<std::size_t>(config.keptRenderers))
                                             : nullptr),
        m_heapReserve(heapReserveFor(config)),
        m_trimmer(std::make_shared<HeapTrimmer>(
            trimTiming(config),
            // What sessions freed beyond the reserve goes back to the system.
            [reserve = m_heapReserve] { trimHeapKeepingReserve(reserve); },
            // The reserve's pages not yet resident written: new ones where
            // the trim grew the heap to keep it (sessions still open).
            [reserve = m_heapReserve] { touchHeapReserve(reserve); })) {
    m_heapWarmUp = std::jthread([reserve = m_heapReserve] { touchHeapReserve(reserve); });
    const pipeline::ViewDescription view;
    if (m_renderers) {
      // One renderer of the default view's size waits for the first session.
      m_renderers->stock(view.width, view.height);
    }
    m_encoderWarmUp = std::jthread(
        [width = view.width, height = view.height] { StreamEncoder::warmUp(width, height); });
  }

  SessionRegistry& sessions() { return m_sessions; }
  bool dataConnected() const { return m_data.connected(); }
  // Null with --kept-renderers 0.
  const RendererShelf* renderers() const { return m_renderers.get(); }
  // Bytes of heap kept touched while idle (0: none).
  std::size_t heapReserve() const { return m_heapReserve; }
  // Drops the crack histories of live files no call has used for a while.
  void reapCrackHistories();
  AttachWatch& attaching() { return m_attaching; }
  const rpc::Authenticator& authenticator() const { return m_authenticator; }
  rpc::AccessLog& accessLog() { return m_log; }
  const RenderServerConfig& config() const { return m_config; }

  grpc::Status OpenSession(grpc::ServerContext* context, const v1::OpenSessionRequest* request,
                           v1::OpenSessionResponse* response) override;
  grpc::Status Stream(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>* stream) override;
  grpc::Status Snapshot(grpc::ServerContext* context, const v1::SnapshotRequest* request,
                        v1::SnapshotResponse* response) override;
  grpc::Status CloseSession(grpc::ServerContext* context, const v1::CloseSessionRequest* request,
                            v1::CloseSessionResponse* /*response*/) override;
  grpc::Status ListFiles(grpc::ServerContext* context, const v1::ListFilesRequest* request,
                         v1::ListFilesResponse* response) override;
  grpc::Status Describe(grpc::ServerContext* context, const v1::DescribeRequest* request,
                        v1::DescribeResponse* response) override;
  grpc::Status StepHistory(grpc::ServerContext* context, const v1::StepHistoryRequest* request,
                           v1::StepHistoryResponse* response) override;

  // The calls' bodies, without a transport: the gRPC handlers below and the
  // web front door (web_front_door.cpp) both run these, so the two doors
  // share the sessions, limits, folder rules and access log.
  Status listFiles(const rpc::Caller& caller, const v1::ListFilesRequest& request,
                   v1::ListFilesResponse& response, rpc::AccessRecord& record, Deadline deadline);
  Status describe(const rpc::Caller& caller, const v1::DescribeRequest& request,
                  v1::DescribeResponse& response, rpc::AccessRecord& record, Deadline deadline);
  Status stepHistory(const rpc::Caller& caller, const v1::StepHistoryRequest& request,
                     v1::StepHistoryResponse& response, rpc::AccessRecord& record,
                     Deadline deadline);
  Status openSession(const rpc::Caller& caller, const v1::OpenSessionRequest& request,
                     v1::OpenSessionResponse& response, rpc::AccessRecord& record);
  Status snapshot(const rpc::Caller& caller, const v1::SnapshotRequest& request,
                  v1::SnapshotResponse& response, rpc::AccessRecord& record, Deadline deadline);
  Status closeSession(const rpc::Caller& caller, const v1::CloseSessionRequest& request);

  // A stream's parts: the session its first message attaches to, each later
  // event applied (converted and checked before it is queued; a bad one is
  // answered by an EventError), and the writer loop until the session
  // closes, another stream attaches, or the sink closes.
  Result<std::shared_ptr<Session>> attachStream(const rpc::Caller& caller,
                                                const v1::ClientEvent& first,
                                                rpc::AccessRecord& record);
  void applyEvent(Session& session, const v1::ClientEvent& event) const;
  Status pumpStream(Session& session, std::uint64_t attachment, StreamSink& sink,
                    rpc::AccessRecord& record);

 private:
  // Every handler: authenticate, run the body at the handler boundary (an
  // exception fails only this call), write the access-log line, answer.
  template <typename Body>
  grpc::Status handle(grpc::ServerContext* context, const char* method, Body&& body);
  Session::SourceOpener opener(const rpc::Caller& caller) const;
  Status addCracks(const rpc::Caller& caller, const v1::StepHistoryRequest& request,
                   v1::StepHistoryResponse& response, Deadline deadline);
  Status runStream(grpc::ServerContext* context,
                   grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>* stream,
                   const rpc::Caller& caller, rpc::AccessRecord& record);

  const RenderServerConfig& m_config;
  rpc::Authenticator m_authenticator;
  dataservice::DataClient m_data;
  rpc::AccessLog& m_log;
  SessionRegistry m_sessions;
  AttachWatch m_attaching;
  CrackHistories m_crackHistories;
  FinishedSeries m_finishedSeries;
  std::shared_ptr<RenderTurns> m_turns;        // shared by every session's frames
  std::shared_ptr<RendererShelf> m_renderers;  // the renderers of ended sessions; may be null
  // --heap-reserve-mb, where threads share the main heap (else 0).
  const std::size_t m_heapReserve;
  std::shared_ptr<HeapTrimmer> m_trimmer;  // the heap, trimmed once sessions stop ending
  std::jthread m_heapWarmUp;               // the reserve's first writing
  std::jthread m_encoderWarmUp;            // libx264's start, joined before the rest goes

  // Quiet for `heapTrimAfterMs`, and at most five times that (5 s at least)
  // after the first session not yet trimmed for, where sessions keep ending.
  static HeapTrimmer::Timing trimTiming(const RenderServerConfig& config) {
    const std::chrono::milliseconds quiet(config.heapTrimAfterMs);
    return {quiet, std::max(std::chrono::milliseconds(5000), 5 * quiet)};
  }

  // The reserve asked for, where a new thread allocates from the main heap
  // (one malloc arena: the services' default where THP is "madvise",
  // common/huge_pages.hpp); a reserve in one thread's heap would serve no
  // other thread.
  static std::size_t heapReserveFor(const RenderServerConfig& config) {
    const std::size_t bytes = static_cast<std::size_t>(std::max(config.heapReserveMb, 0)) << 20;
    if (bytes == 0 || !threadsShareMainHeap() || !setHeapReserveThresholds(bytes)) {
      return 0;
    }
    return bytes;
  }
};

}  // namespace crackvis::service
