// RenderClient's construction and its connection: the TLS channel, the
// authorization every call carries, and the unary calls of the file browser
// (ListFiles, StepHistory, Describe). render_client_impl.hpp says where the
// rest of the client lives.
#include <chrono>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "render_client_impl.hpp"
#include <crackvis/common/certificates.hpp>
#include <crackvis/rpc/connection_advice.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/tls/channel.hpp>

namespace crackvis::client {
namespace {

// A TLS file of the connection, with the defaults' fallback to the
// installed certificates and a message naming the option that sets it.
Result<std::string> readTlsFile(const QString& path, const char* what, const char* flag) {
  return readCertificateFile(path.toStdString(), what,
                             fmt::format("{} or in File > Connect", flag));
}

// crackvis-render as the user named it, for connection_advice's messages;
// this client has no plaintext mode.
rpc::Peer renderPeer(const QString& address) {
  return {rpc::ServerKind::kRender, address.toStdString(), false, "--", false};
}

}  // namespace

Status RenderClient::Impl::failure(const grpc::Status& status, const char* call) const {
  return rpc::fromGrpcStatus(status, call, renderPeer(settings.address), channel);
}

void RenderClient::Impl::authorize(grpc::ClientContext& context) const {
  if (!settings.token.isEmpty()) {
    context.AddMetadata("authorization", "Bearer " + settings.token.toStdString());
  }
}

RenderClient::RenderClient(QObject* parent) : QObject(parent), m_impl(std::make_unique<Impl>()) {
  qRegisterMetaType<crackvis::client::FrameInfo>();
  m_impl->owner = this;
}

RenderClient::~RenderClient() {
  if (m_impl->historyCall.joinable()) {
    m_impl->historyContext->TryCancel();
    m_impl->historyCall.join();  // its answer, posted to this object, is dropped with it
  }
  closeSession();
}

Status RenderClient::connectTo(const ConnectionSettings& settings) {
  closeSession();
  CRACKVIS_RETURN_IF_ERROR(rpc::checkHostPort("address", settings.address.toStdString()));
  auto ca = readTlsFile(settings.caPath, "CA certificate", "--ca");
  auto cert = readTlsFile(settings.certPath, "client certificate", "--cert");
  auto key = readTlsFile(settings.keyPath, "client key", "--key");
  for (const auto* file : {&ca, &cert, &key}) {
    if (!*file) {
      return file->status();
    }
  }
  tls::ChannelOptions options;
  options.target = settings.address.toStdString();
  options.material = tls::TlsMaterial{*ca, *cert, *key, {}};
  // A restarted server is found again within about two seconds, not after
  // gRPC's backoff of up to two minutes.
  options.initialReconnectBackoffMs = 100;
  options.maxReconnectBackoffMs = 2000;
  auto created = tls::createChannel(options);
  if (!created) {
    return created.status();
  }
  auto channel = std::move(created).value();
  auto stub = v1::RenderService::NewStub(channel);
  // One round trip that needs the server and our certificate: ListFiles,
  // on the channel's connection (gRPC 1.51 can fail an attempt in progress:
  // rpc::awaitConnection).
  const auto deadline = std::chrono::system_clock::now() + std::chrono::seconds(10);
  rpc::awaitConnection(*channel, options.target, deadline);
  grpc::ClientContext context;
  context.set_deadline(deadline);
  if (!settings.token.isEmpty()) {
    context.AddMetadata("authorization", "Bearer " + settings.token.toStdString());
  }
  v1::ListFilesResponse files;
  CRACKVIS_RETURN_IF_ERROR(
      rpc::fromGrpcStatus(stub->ListFiles(&context, v1::ListFilesRequest(), &files),
                          fmt::format("connecting to {}", settings.address.toStdString()),
                          renderPeer(settings.address), channel));
  m_impl->settings = settings;
  m_impl->channel = std::move(channel);
  m_impl->stub = std::move(stub);
  return Status::ok();
}

bool RenderClient::connected() const {
  return m_impl->stub != nullptr;
}
const ConnectionSettings& RenderClient::settings() const {
  return m_impl->settings;
}

Result<std::vector<FileEntry>> RenderClient::listFiles() {
  v1::ListFilesRequest request;
  request.set_recursive(true);
  v1::ListFilesResponse response;
  CRACKVIS_RETURN_IF_ERROR(
      m_impl->unary("ListFiles", response, [&](grpc::ClientContext& context, auto& out) {
        return m_impl->stub->ListFiles(&context, request, &out);
      }));
  std::vector<FileEntry> out;
  for (const auto& file : response.files()) {
    out.push_back({QString::fromStdString(file.path()), static_cast<qint64>(file.size_bytes()),
                   file.is_hdf5()});
  }
  return out;
}

namespace {

v1::StepHistoryRequest historyRequest(const QString& file, const QString& cracks) {
  v1::StepHistoryRequest request;
  request.set_file(file.toStdString());
  request.set_cracks(cracks.toStdString());
  return request;
}

StepHistory historyOf(const v1::StepHistoryResponse& response) {
  StepHistory history;
  history.time.assign(response.time().begin(), response.time().end());
  history.brokenBonds.assign(response.broken_bonds().begin(), response.broken_bonds().end());
  history.bondCount = response.bond_count();
  for (const v1::StepSeries& series : response.scalars()) {
    history.scalarNames << QString::fromStdString(series.name());
    history.scalars.emplace_back(series.values().begin(), series.values().end());
  }
  return history;
}

}  // namespace

void RenderClient::requestStepHistory(const QString& file, const QString& cracks) {
  if (m_impl->historyCall.joinable()) {
    m_impl->pendingHistory = {file, cracks};
    return;
  }
  startStepHistory(file, cracks);
}

// The call runs on a thread of its own, with a stub of its own on the
// connection's channel (a reconnect may replace the client's stub meanwhile),
// and posts its answer back to this object's thread.
void RenderClient::startStepHistory(const QString& file, const QString& cracks) {
  if (!m_impl->channel) {
    emit stepHistoryReady(file, cracks, {}, tr("not connected"));
    return;
  }
  auto context = std::make_shared<grpc::ClientContext>();
  m_impl->authorize(*context);
  m_impl->historyContext = context;
  m_impl->historyCall = std::thread([this, channel = m_impl->channel, context,
                                     request = historyRequest(file, cracks), file, cracks] {
    auto stub = v1::RenderService::NewStub(channel);
    auto response = std::make_shared<v1::StepHistoryResponse>();
    const grpc::Status status = stub->StepHistory(context.get(), request, response.get());
    QMetaObject::invokeMethod(
        this,
        [this, status, response, file, cracks] {
          const Status outcome =
              status.ok() ? Status::ok() : m_impl->failure(status, "StepHistory");
          finishStepHistory(file, cracks,
                            outcome ? QString() : QString::fromStdString(outcome.message()),
                            outcome ? historyOf(*response) : StepHistory{});
        },
        Qt::QueuedConnection);
  });
}

void RenderClient::finishStepHistory(const QString& file, const QString& cracks,
                                     const QString& error, const StepHistory& history) {
  m_impl->historyCall.join();
  m_impl->historyContext.reset();
  emit stepHistoryReady(file, cracks, history, error);
  if (auto next = std::exchange(m_impl->pendingHistory, std::nullopt)) {
    startStepHistory(next->first, next->second);
  }
}

Result<FileSummary> RenderClient::describe(const QString& file) {
  v1::DescribeRequest request;
  request.set_file(file.toStdString());
  v1::DescribeResponse response;
  CRACKVIS_RETURN_IF_ERROR(
      m_impl->unary("Describe", response, [&](grpc::ClientContext& context, auto& out) {
        return m_impl->stub->Describe(&context, request, &out);
      }));
  FileSummary summary;
  summary.file = file;
  summary.format = QString::fromStdString(response.format());
  summary.sizeBytes = static_cast<qint64>(response.size_bytes());
  summary.steps = response.steps_size();
  if (summary.steps > 0) {
    summary.firstTime = response.steps(0).time();
    summary.lastTime = response.steps(summary.steps - 1).time();
  }
  for (const auto& dataset : response.datasets()) {
    QStringList shape;
    for (auto extent : dataset.shape()) {
      shape << QString::number(extent);
    }
    if (dataset.path() == "/particles/radius" && dataset.shape_size() == 1) {
      summary.particles = static_cast<qint64>(dataset.shape(0));
    }
    if (dataset.path() == "/bonds/pairs" && dataset.shape_size() >= 1) {
      summary.bonds = static_cast<qint64>(dataset.shape(0));
    }
    for (const auto& [folder, names] :
         {std::pair{"/extra/particles/", &summary.particleExtras},
          std::pair{"/steps/000000/extra/particles/", &summary.particleExtras},
          std::pair{"/extra/bonds/", &summary.bondExtras},
          std::pair{"/steps/000000/extra/bonds/", &summary.bondExtras}}) {
      const std::string_view path = dataset.path();
      if (path.rfind(folder, 0) == 0) {
        const QString name = QString::fromStdString(std::string(path.substr(std::strlen(folder))));
        if (!names->contains(name)) {
          *names << name;
        }
      }
    }
    // Per-step arrays repeat in every step: list the first step's only.
    const bool laterStep =
        dataset.path().rfind("/steps/", 0) == 0 && dataset.path().rfind("/steps/000000/", 0) != 0;
    if (!laterStep) {
      summary.arrays << QStringLiteral("%1 %2 [%3]")
                            .arg(QString::fromStdString(dataset.path()),
                                 QString::fromStdString(dataset.dtype_name()), shape.join(", "));
    }
  }
  return summary;
}

}  // namespace crackvis::client
