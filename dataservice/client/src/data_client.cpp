#include <algorithm>
#include <atomic>
#include <chrono>

#include <fmt/format.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include "chunk_receiver.hpp"
#include "crackvis/v1/data.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "grpc_convert.hpp"
#include <crackvis/common/base64.hpp>
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/rpc/connection_advice.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/tls/channel.hpp>

namespace crackvis::dataservice {
namespace v1 = crackvis::v1;

namespace {

std::vector<std::uint64_t> toVector(const google::protobuf::RepeatedField<std::uint64_t>& field) {
  return {field.begin(), field.end()};
}

AttributeInfo fromProto(const v1::Attribute& in) {
  AttributeInfo out;
  out.name = in.name();
  out.dtype = dataTypeFromInt(in.dtype());
  out.shape = toVector(in.shape());
  out.truncated = in.truncated();
  switch (in.value_case()) {
    case v1::Attribute::kText:
      out.value = in.text();
      break;
    case v1::Attribute::kIntegers:
      out.value =
          std::vector<std::int64_t>(in.integers().values().begin(), in.integers().values().end());
      break;
    case v1::Attribute::kFloats:
      out.value = std::vector<double>(in.floats().values().begin(), in.floats().values().end());
      break;
    case v1::Attribute::VALUE_NOT_SET:
      break;
  }
  return out;
}

}  // namespace

FileDescription fromProto(const v1::DescribeResponse& in) {
  FileDescription out;
  out.file = in.file();
  out.sizeBytes = in.size_bytes();
  for (const v1::Group& group : in.groups()) {
    GroupInfo g{group.path(), {}};
    for (const v1::Attribute& attribute : group.attributes()) {
      g.attributes.push_back(fromProto(attribute));
    }
    out.groups.push_back(std::move(g));
  }
  for (const v1::Dataset& dataset : in.datasets()) {
    DatasetInfo d;
    d.path = dataset.path();
    d.dtype = dataTypeFromInt(dataset.dtype());
    d.dtypeName = dataset.dtype_name();
    d.shape = toVector(dataset.shape());
    d.chunkShape = toVector(dataset.chunk_shape());
    for (const v1::Attribute& attribute : dataset.attributes()) {
      d.attributes.push_back(fromProto(attribute));
    }
    out.datasets.push_back(std::move(d));
  }
  out.format = in.format();
  out.formatVersion = in.format_version();
  for (const v1::Step& step : in.steps()) {
    out.steps.push_back({step.index(), step.time(), step.group()});
  }
  out.buildIndex();
  return out;
}

struct DataClient::Impl {
  ClientOptions options;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::DataService::Stub> stub;
  std::unique_ptr<grpc::health::v1::Health::Stub> health;
  // Read goes through grpc's generic stub, which hands each chunk over as
  // the byte buffers it arrived in (see receiveChunk).
  std::unique_ptr<grpc::TemplatedGenericStub<v1::ReadRequest, grpc::ByteBuffer>> readStub;
  std::string authorization;
  // The data bytes of every Read's chunks as they came (packed or not).
  std::atomic<std::uint64_t> readWireBytes{0};

  // crackvis-data as the user named it, for connection_advice's messages.
  rpc::Peer peer(rpc::ServerKind kind = rpc::ServerKind::kData) const {
    return {kind, options.target, options.insecure, options.tls.flagPrefix, true};
  }
  Status failure(const grpc::Status& status, const char* call,
                 rpc::ServerKind kind = rpc::ServerKind::kData) const {
    return rpc::fromGrpcStatus(status, call, peer(kind), channel);
  }

  // The options' timeout from now, or `deadline` when it comes first; a
  // channel not connected yet is given its connection first (gRPC 1.51 can
  // fail an attempt in progress: rpc::awaitConnection).
  void prepare(grpc::ClientContext& context, Deadline deadline = Deadline::max()) const {
    const Deadline until =
        std::min(deadline, std::chrono::system_clock::now() +
                               std::chrono::duration_cast<std::chrono::system_clock::duration>(
                                   std::chrono::duration<double>(options.timeoutSeconds)));
    rpc::awaitConnection(*channel, options.target, until);
    context.set_deadline(until);
    if (!authorization.empty()) {
      context.AddMetadata("authorization", authorization);
    }
  }

  // One unary call for crackvis-render (DataClient::resolve, the relays):
  // `invoke` makes it on a prepared context.
  template <typename Invoke>
  Status relay(const char* call, Deadline deadline, Invoke&& invoke) const {
    grpc::ClientContext context;
    prepare(context, deadline);
    return rpc::fromGrpcStatus(invoke(context), fmt::format("crackvis-data {}", call), peer(),
                               channel);
  }
};

void DataClient::startConnecting() const {
  (void)m_impl->channel->GetState(/*try_to_connect=*/true);
}

bool DataClient::connected() const {
  return m_impl->channel->GetState(false) == GRPC_CHANNEL_READY;
}

Result<DataClient> DataClient::connect(const ClientOptions& options) {
  auto impl = std::make_shared<Impl>();
  impl->options = options;
  tls::ChannelOptions channel;
  channel.target = options.target;
  channel.insecure = options.insecure;
  channel.files = options.tls;
  channel.serverName = options.serverName;
  // Each client its own connection: 16 clients are 16 TCP connections, as
  // they would be from 16 machines.
  channel.ownConnection = true;
  // A view's Read is a few MiB on a fresh stream: a large initial window
  // lets the server send it without waiting for window updates.
  channel.streamWindowBytes = 16 << 20;
  // Failed connection attempts are retried about 5 s apart at most (4-6 s
  // with gRPC's jitter; its default grows to 2 minutes): a client connecting
  // early (startConnecting) to a crackvis-data that starts later reaches it
  // at the next try instead of failing its calls for minutes. Each failed
  // try is one line of gRPC's in the log (a TLS misconfiguration: one every
  // 5 s or so), so not more often. A connection that worked and was lost is
  // made again by the next call.
  channel.maxReconnectBackoffMs = 5000;
  auto created = tls::createChannel(channel);
  if (!created) {
    return created.status();
  }
  if (!options.token.empty()) {
    impl->authorization = "Bearer " + options.token;
  } else if (!options.user.empty()) {
    impl->authorization = "Basic " + base64Encode(options.user + ":" + options.password);
  }
  impl->channel = std::move(created).value();
  impl->stub = v1::DataService::NewStub(impl->channel);
  impl->health = grpc::health::v1::Health::NewStub(impl->channel);
  impl->readStub = std::make_unique<grpc::TemplatedGenericStub<v1::ReadRequest, grpc::ByteBuffer>>(
      impl->channel);
  return DataClient(std::move(impl));
}

const ClientOptions& DataClient::options() const {
  return m_impl->options;
}

std::uint64_t DataClient::readWireBytes() const {
  return m_impl->readWireBytes.load();
}

Status DataClient::checkHealth(const std::string& service) const {
  grpc::ClientContext context;
  m_impl->prepare(context);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = m_impl->health->Check(&context, request, &response);
  if (status.error_code() == grpc::StatusCode::NOT_FOUND && !service.empty()) {
    // The health service knows no such name: say what answered instead.
    const rpc::ServerKind kind = rpc::identifyServer(m_impl->channel);
    return notFound(fmt::format("{}{} does not serve '{}'", m_impl->options.target,
                                kind == rpc::ServerKind::kAny
                                    ? std::string()
                                    : fmt::format(" (a {})", rpc::programName(kind)),
                                service));
  }
  if (!status.ok()) {
    // Health is served by both kinds of server.
    return m_impl->failure(status, "health check", rpc::ServerKind::kAny);
  }
  if (response.status() != grpc::health::v1::HealthCheckResponse::SERVING) {
    return Status(
        StatusCode::kUnavailable,
        fmt::format("health check: server reports {}",
                    grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status())));
  }
  return Status::ok();
}

std::string DataClient::serverProgram() const {
  const rpc::ServerKind kind = rpc::identifyServer(m_impl->channel);
  return kind == rpc::ServerKind::kAny ? std::string() : std::string(rpc::programName(kind));
}

Result<std::vector<FileEntry>> DataClient::listFiles(const std::string& folder,
                                                     bool recursive) const {
  grpc::ClientContext context;
  m_impl->prepare(context);
  v1::ListFilesRequest request;
  request.set_folder(folder);
  request.set_recursive(recursive);
  v1::ListFilesResponse response;
  const grpc::Status status = m_impl->stub->ListFiles(&context, request, &response);
  if (!status.ok()) {
    return m_impl->failure(status, "ListFiles");
  }
  std::vector<FileEntry> files;
  for (const v1::FileEntry& entry : response.files()) {
    files.push_back(
        {entry.path(), entry.size_bytes(), entry.modified_unix_seconds(), entry.is_hdf5()});
  }
  return files;
}

Result<FileDescription> DataClient::describe(const std::string& file, bool uncached) const {
  grpc::ClientContext context;
  m_impl->prepare(context);
  v1::DescribeRequest request;
  request.set_file(file);
  request.set_uncached(uncached);
  v1::DescribeResponse response;
  const grpc::Status status = m_impl->stub->Describe(&context, request, &response);
  if (!status.ok()) {
    return m_impl->failure(status, "Describe");
  }
  return fromProto(response);
}

Result<std::string> DataClient::resolve(const std::string& file, Deadline deadline) const {
  v1::ResolveRequest request;
  request.set_file(file);
  v1::ResolveResponse response;
  CRACKVIS_RETURN_IF_ERROR(m_impl->relay("Resolve", deadline, [&](grpc::ClientContext& context) {
    return m_impl->stub->Resolve(&context, request, &response);
  }));
  return response.resolved_file();
}

Status DataClient::relayListFiles(const v1::ListFilesRequest& request,
                                  v1::ListFilesResponse& response, Deadline deadline) const {
  return m_impl->relay("ListFiles", deadline, [&](grpc::ClientContext& context) {
    return m_impl->stub->ListFiles(&context, request, &response);
  });
}

Status DataClient::relayDescribe(const v1::DescribeRequest& request, v1::DescribeResponse& response,
                                 Deadline deadline) const {
  return m_impl->relay("Describe", deadline, [&](grpc::ClientContext& context) {
    return m_impl->stub->Describe(&context, request, &response);
  });
}

// One Read call on its own completion queue, driven from the caller's
// thread as a synchronous call would be: each operation is waited for before
// the next starts. The queue is declared first so that it outlives the call.
struct DataClient::PendingRead::Call {
  grpc::CompletionQueue queue;
  grpc::ClientContext context;
  std::unique_ptr<grpc::ClientAsyncReaderWriter<v1::ReadRequest, grpc::ByteBuffer>> stream;
  std::size_t slabs = 0;
  bool acceptsPacked = false;
  std::shared_ptr<DataClient::Impl> client;  // for the advice on a failure, the byte count
  bool requestSent = false;
  bool finished = false;

  // Waits for the one operation in flight; true when it succeeded.
  bool await() {
    void* tag = nullptr;
    bool ok = false;
    return queue.Next(&tag, &ok) && ok;
  }

  grpc::Status finish() {
    if (!requestSent) {
      await();  // the request's write, which may have failed
      requestSent = true;
    }
    grpc::Status status;
    stream->Finish(&status, nullptr);
    await();
    queue.Shutdown();
    void* tag = nullptr;
    bool ok = false;
    while (queue.Next(&tag, &ok)) {
    }
    finished = true;
    return status;
  }

  ~Call() {
    if (!finished) {
      context.TryCancel();
      finish();
    }
  }
};

DataClient::PendingRead::PendingRead(std::unique_ptr<Call> call) : m_call(std::move(call)) {}
DataClient::PendingRead::PendingRead(PendingRead&&) noexcept = default;
DataClient::PendingRead& DataClient::PendingRead::operator=(PendingRead&&) noexcept = default;
DataClient::PendingRead::~PendingRead() = default;

DataClient::PendingRead DataClient::startRead(const std::string& file,
                                              const std::vector<Hyperslab>& slabs) const {
  v1::ReadRequest request;
  request.set_file(file);
  for (const Hyperslab& slab : slabs) {
    v1::Hyperslab* out = request.add_slabs();
    out->set_dataset(slab.dataset);
    out->mutable_start()->Add(slab.start.begin(), slab.start.end());
    out->mutable_count()->Add(slab.count.begin(), slab.count.end());
  }
  if (m_impl->options.packedReads) {
    request.add_accept_encodings(v1::CHUNK_ENCODING_PACKED);
  }
  auto call = std::make_unique<PendingRead::Call>();
  call->slabs = slabs.size();
  call->acceptsPacked = m_impl->options.packedReads;
  call->client = m_impl;
  m_impl->prepare(call->context);
  // The initial metadata leaves with the request in one batch, and only
  // that batch completes (StartCall then posts no operation of its own).
  call->context.set_initial_metadata_corked(true);
  static const std::string kMethod = fmt::format("/{}/Read", v1::DataService::service_full_name());
  call->stream = m_impl->readStub->PrepareCall(&call->context, kMethod, &call->queue);
  call->stream->StartCall(nullptr);
  call->stream->WriteLast(request, grpc::WriteOptions(), nullptr);
  return PendingRead(std::move(call));
}

Status DataClient::PendingRead::receive(const SlabSink& sink, const ChunkCallback& arrived) {
  if (!m_call || m_call->requestSent) {
    return internalError("Read: receive() called twice");
  }
  Call& call = *m_call;
  call.await();  // the request's write; a failure shows in Finish's status
  call.requestSent = true;
  SlabReceiver receiver(sink, call.slabs, call.acceptsPacked);
  Status error;
  grpc::ByteBuffer message;
  while (error.isOk()) {
    call.stream->Read(&message, nullptr);
    if (!call.await()) {
      break;  // the stream ended; Finish tells how
    }
    auto placed = receiveChunk(message, receiver);
    message.Clear();
    if (!placed) {
      error = placed.status();
      break;
    }
    call.client->readWireBytes += placed->wireBytes;
    if (arrived) {
      error = arrived(placed->slab, placed->offset, placed->bytes);
    }
  }
  if (!error.isOk()) {
    call.context.TryCancel();
  }
  const grpc::Status status = call.finish();
  if (!error.isOk()) {
    return error;
  }
  if (!status.ok()) {
    return call.client->failure(status, "Read");
  }
  return receiver.complete();
}

Status DataClient::readInto(const std::string& file, const std::vector<Hyperslab>& slabs,
                            const SlabSink& sink) const {
  return startRead(file, slabs).receive(sink);
}

Result<std::vector<TypedArray>> DataClient::read(const std::string& file,
                                                 const std::vector<Hyperslab>& slabs) const {
  std::vector<TypedArray> arrays(slabs.size());
  for (std::size_t i = 0; i < slabs.size(); ++i) {
    arrays[i].dataset = slabs[i].dataset;
  }
  CRACKVIS_RETURN_IF_ERROR(readInto(file, slabs, [&](const SlabHeader& slab) -> Result<std::byte*> {
    TypedArray& array = arrays[slab.index];
    array.dtype = slab.dtype;
    array.shape = slab.shape;
    array.bytes.resize(slab.bytes);
    return array.bytes.data();
  }));
  return arrays;
}

Result<std::uint64_t> DataClient::fetch(const std::string& file, const FetchSink& sink) const {
  grpc::ClientContext context;
  m_impl->prepare(context);
  v1::FetchRequest request;
  request.set_file(file);
  auto reader = m_impl->stub->Fetch(&context, request);
  v1::FetchChunk chunk;
  std::uint64_t received = 0;
  std::uint64_t fileBytes = 0;
  Status sinkError;
  while (reader->Read(&chunk)) {
    fileBytes = chunk.file_bytes();
    if (chunk.offset() != received) {
      sinkError = internalError(
          fmt::format("Fetch: chunk at offset {}, expected {}", chunk.offset(), received));
    } else if (sink) {
      sinkError = sink(chunk.offset(), reinterpret_cast<const std::byte*>(chunk.data().data()),
                       chunk.data().size(), fileBytes);
    }
    if (!sinkError.isOk()) {
      context.TryCancel();
      break;
    }
    received += chunk.data().size();
  }
  const grpc::Status status = reader->Finish();
  if (!sinkError.isOk()) {
    return sinkError;
  }
  if (!status.ok()) {
    return m_impl->failure(status, "Fetch");
  }
  if (received != fileBytes) {
    return internalError(
        fmt::format("Fetch: stream ended after {} of {} bytes", received, fileBytes));
  }
  return received;
}

}  // namespace crackvis::dataservice
