#include <chrono>

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include "crackvis/v1/data.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "grpc_convert.hpp"
#include <crackvis/dataservice/data_client.hpp>

namespace crackvis::dataservice {
namespace v1 = crackvis::v1;

namespace {

const char* grpcCodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::UNKNOWN:
      return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS:
      return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED:
      return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED:
      return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE:
      return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED:
      return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS:
      return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    default:
      return "UNKNOWN";
  }
}

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

Status fromGrpcStatus(const grpc::Status& status, const std::string& call) {
  if (status.ok()) {
    return Status::ok();
  }
  const std::string& message = status.error_message();
  switch (status.error_code()) {
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::OUT_OF_RANGE:
      return {StatusCode::kInvalidArgument, message};
    case grpc::StatusCode::NOT_FOUND:
      return {StatusCode::kNotFound, message};
    case grpc::StatusCode::FAILED_PRECONDITION:
      return {StatusCode::kFailedPrecondition, message};
    case grpc::StatusCode::PERMISSION_DENIED:
      return {StatusCode::kPermissionDenied, message};
    case grpc::StatusCode::UNAUTHENTICATED:
      return {StatusCode::kUnauthenticated, message};
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return {StatusCode::kResourceExhausted, message};
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::CANCELLED:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
    case grpc::StatusCode::ABORTED:
      return {StatusCode::kUnavailable,
              fmt::format("{}: {}: {}", call, grpcCodeName(status.error_code()), message)};
    default:
      return {StatusCode::kInternal,
              fmt::format("{}: {}: {}", call, grpcCodeName(status.error_code()), message)};
  }
}

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
  return out;
}

struct DataClient::Impl {
  ClientOptions options;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::DataService::Stub> stub;
  std::unique_ptr<grpc::health::v1::Health::Stub> health;
  std::string authorization;

  void prepare(grpc::ClientContext& context) const {
    context.set_deadline(std::chrono::system_clock::now() +
                         std::chrono::duration_cast<std::chrono::system_clock::duration>(
                             std::chrono::duration<double>(options.timeoutSeconds)));
    if (!authorization.empty()) {
      context.AddMetadata("authorization", authorization);
    }
  }
};

Result<DataClient> DataClient::connect(const ClientOptions& options) {
  auto impl = std::make_shared<Impl>();
  impl->options = options;
  grpc::ChannelArguments arguments;
  // Each client its own connection: 16 clients are 16 TCP connections, as
  // they would be from 16 machines.
  arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  arguments.SetMaxReceiveMessageSize(64 << 20);
  // A view's Read is a few MiB on a fresh stream: a large initial window
  // lets the server send it without waiting for window updates.
  arguments.SetInt(GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES, 16 << 20);
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (options.insecure) {
    credentials = grpc::InsecureChannelCredentials();
  } else {
    auto material = loadTlsMaterial(options.tls);
    if (!material) {
      return material.status();
    }
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = material->caPem;
    ssl.pem_cert_chain = material->certPem;
    ssl.pem_private_key = material->keyPem;
    credentials = grpc::SslCredentials(ssl);
    if (!options.serverName.empty()) {
      arguments.SetSslTargetNameOverride(options.serverName);
    }
  }
  if (!options.token.empty()) {
    impl->authorization = "Bearer " + options.token;
  } else if (!options.user.empty()) {
    const std::string plain = options.user + ":" + options.password;
    std::string encoded;
    static constexpr char kAlphabet[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < plain.size(); i += 3) {
      const auto byte = [&](size_t k) {
        return k < plain.size() ? static_cast<unsigned>(static_cast<unsigned char>(plain[k])) : 0u;
      };
      const unsigned triple = (byte(i) << 16) | (byte(i + 1) << 8) | byte(i + 2);
      encoded += kAlphabet[(triple >> 18) & 63];
      encoded += kAlphabet[(triple >> 12) & 63];
      encoded += i + 1 < plain.size() ? kAlphabet[(triple >> 6) & 63] : '=';
      encoded += i + 2 < plain.size() ? kAlphabet[triple & 63] : '=';
    }
    impl->authorization = "Basic " + encoded;
  }
  impl->channel = grpc::CreateCustomChannel(options.target, credentials, arguments);
  if (!impl->channel) {
    return invalidArgument(fmt::format("cannot create a channel to '{}'", options.target));
  }
  impl->stub = v1::DataService::NewStub(impl->channel);
  impl->health = grpc::health::v1::Health::NewStub(impl->channel);
  return DataClient(std::move(impl));
}

const ClientOptions& DataClient::options() const {
  return m_impl->options;
}

Status DataClient::checkHealth(const std::string& service) const {
  grpc::ClientContext context;
  m_impl->prepare(context);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = m_impl->health->Check(&context, request, &response);
  if (!status.ok()) {
    return fromGrpcStatus(status, "health check");
  }
  if (response.status() != grpc::health::v1::HealthCheckResponse::SERVING) {
    return Status(
        StatusCode::kUnavailable,
        fmt::format("health check: server reports {}",
                    grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status())));
  }
  return Status::ok();
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
    return fromGrpcStatus(status, "ListFiles");
  }
  std::vector<FileEntry> files;
  for (const v1::FileEntry& entry : response.files()) {
    files.push_back(
        {entry.path(), entry.size_bytes(), entry.modified_unix_seconds(), entry.is_hdf5()});
  }
  return files;
}

Result<FileDescription> DataClient::describe(const std::string& file) const {
  grpc::ClientContext context;
  m_impl->prepare(context);
  v1::DescribeRequest request;
  request.set_file(file);
  v1::DescribeResponse response;
  const grpc::Status status = m_impl->stub->Describe(&context, request, &response);
  if (!status.ok()) {
    return fromGrpcStatus(status, "Describe");
  }
  return fromProto(response);
}

Status DataClient::readInto(const std::string& file, const std::vector<Hyperslab>& slabs,
                            const SlabSink& sink) const {
  grpc::ClientContext context;
  m_impl->prepare(context);
  v1::ReadRequest request;
  request.set_file(file);
  for (const Hyperslab& slab : slabs) {
    v1::Hyperslab* out = request.add_slabs();
    out->set_dataset(slab.dataset);
    out->mutable_start()->Add(slab.start.begin(), slab.start.end());
    out->mutable_count()->Add(slab.count.begin(), slab.count.end());
  }
  struct Destination {
    std::byte* data = nullptr;
    std::uint64_t bytes = 0;
    std::uint64_t received = 0;
    bool started = false;
  };
  std::vector<Destination> destinations(slabs.size());
  auto reader = m_impl->stub->Read(&context, request);
  v1::ReadChunk chunk;
  Status error;
  while (error.isOk() && reader->Read(&chunk)) {
    const std::size_t index = chunk.slab_index();
    if (index >= destinations.size()) {
      error = internalError(fmt::format("Read: chunk for slab {} of {}", index, slabs.size()));
      break;
    }
    Destination& destination = destinations[index];
    if (!destination.started) {
      SlabHeader header{index, dataTypeFromInt(chunk.dtype()), toVector(chunk.shape()),
                        chunk.slab_bytes()};
      std::uint64_t expected = elementSize(header.dtype);
      for (auto d : header.shape) {
        expected *= d;
      }
      if (expected != header.bytes) {
        error = internalError(
            fmt::format("Read: slab {} announces {} bytes for its shape and dtype, expected {}",
                        index, header.bytes, expected));
        break;
      }
      auto buffer = sink(header);
      if (!buffer) {
        error = buffer.status();
        break;
      }
      destination = {*buffer, header.bytes, 0, true};
    }
    const std::string& data = chunk.data();
    if (chunk.offset() != destination.received ||
        data.size() > destination.bytes - destination.received) {
      error = internalError(fmt::format(
          "Read: slab {}: chunk at offset {} out of order or too long", index, chunk.offset()));
      break;
    }
    std::memcpy(destination.data + chunk.offset(), data.data(), data.size());
    destination.received += data.size();
  }
  if (!error.isOk()) {
    context.TryCancel();
  }
  const grpc::Status status = reader->Finish();
  if (!error.isOk()) {
    return error;
  }
  if (!status.ok()) {
    return fromGrpcStatus(status, "Read");
  }
  for (std::size_t i = 0; i < destinations.size(); ++i) {
    if (destinations[i].started && destinations[i].received != destinations[i].bytes) {
      return internalError(fmt::format("Read: slab {} ended after {} of {} bytes", i,
                                       destinations[i].received, destinations[i].bytes));
    }
  }
  return Status::ok();
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
    return fromGrpcStatus(status, "Fetch");
  }
  if (received != fileBytes) {
    return internalError(
        fmt::format("Fetch: stream ended after {} of {} bytes", received, fileBytes));
  }
  return received;
}

}  // namespace crackvis::dataservice
