// The RenderService over gRPC (synchronous API: a stream's writer loop and
// its reader thread each block on their own side of the call, so a slow
// client holds up neither the session's rendering nor other calls). Each
// handler authenticates the caller, applies its folder rules, and answers
// from crackvis-data or a session; RenderServer (render_server.cpp) hosts
// it. Private to the service library.
#pragma once

#include <grpcpp/grpcpp.h>

#include "crackvis/v1/render.grpc.pb.h"
#include "session_registry.hpp"
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/rpc_server/access_log.hpp>
#include <crackvis/rpc_server/call.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/service/render_server.hpp>
#include <crackvis/service/session.hpp>

namespace crackvis::service {

// The program's name in log lines, the access log and the health service.
inline constexpr const char* kProgram = "crackvis-render";

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

 private:
  // Every handler: authenticate, run the body at the handler boundary (an
  // exception fails only this call), write the access-log line, answer.
  template <typename Body>
  grpc::Status handle(grpc::ServerContext* context, const char* method, Body&& body);
  Session::SourceOpener opener(const rpc::Caller& caller) const;
  Status openSession(const grpc::ServerContext& /*context*/, const rpc::Caller& caller,
                     const v1::OpenSessionRequest& request, v1::OpenSessionResponse& response,
                     rpc::AccessRecord& record);
  Status runStream(grpc::ServerContext* context,
                   grpc::ServerReaderWriter<v1::ServerMessage, v1::ClientEvent>* stream,
                   const rpc::Caller& caller, rpc::AccessRecord& record);
  Status snapshot(const grpc::ServerContext& context, const rpc::Caller& caller,
                  const v1::SnapshotRequest& request, v1::SnapshotResponse& response,
                  rpc::AccessRecord& record);

  const RenderServerConfig& m_config;
  rpc::Authenticator m_authenticator;
  dataservice::DataClient m_data;
  rpc::AccessLog& m_log;
  SessionRegistry m_sessions;
  AttachWatch m_attaching;
};

}  // namespace crackvis::service
