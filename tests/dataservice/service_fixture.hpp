// What the data service's tests share: certificates made by
// certs/make-dev-certs.sh once per test process, a data root with sample
// files (valid, damaged, linked out of the root) made in code, and helpers
// to start a real server on a loopback port the OS chooses and to connect.
#pragma once

#include <cstring>
#include <filesystem>
#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "crackvis/v1/data.grpc.pb.h"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/dataservice_service/data_server.hpp>

namespace crackvis::testing {

// Directory with ca, server, client, crackvis-render, other-ca,
// other-client and expired-client certificates (.pem/.key).
const std::filesystem::path& certificateDir();
tls::TlsFiles serverTls();
// A client's files: `name` is "client", "crackvis-render", "other-client" or
// "expired-client"; `ca` is the CA the client trusts for the server.
tls::TlsFiles clientTls(const std::string& name = "client", const std::string& ca = "ca");

// The data root, made once per process before any server starts:
//   run.h5            3D sample, 3 steps, optional arrays      (sample3d)
//   flat/run2d.h5     2D sample, 2 steps
//   many.h5           3D sample, 16 steps                        (sample16)
//   big.h5            /ramp float64[2097152] = 16 MiB (value i/2), /wide float64[3,150000]
//   notes.txt         not HDF5
//   truncated.h5      run.h5 cut to half its size
//   alice/a.h5, bob/b.h5          copies of run.h5
//   alice/bob-link.h5 -> ../bob/b.h5       (inside the root, across users)
//   inside-link.h5    -> run.h5            (allowed)
//   escape.h5         -> <outside>/secret.h5 (leaves the root)
//   extlink.h5        HDF5 with /outside, an external link to <outside>/secret.h5:/data
struct SampleRoot {
  TempDir root;
  TempDir outside;
  SampleData sample3d;
  SampleData sample16;
  std::string file(const std::string& relative) const { return (root.path() / relative).string(); }
};
const SampleRoot& sampleRoot();

// 127.0.0.1:0, the sample root, mutual TLS, no access log.
dataservice::ServerConfig baseConfig();
std::unique_ptr<dataservice::DataServer> startServer(const dataservice::ServerConfig& config);
dataservice::ClientOptions clientOptions(const dataservice::DataServer& server,
                                         const std::string& certificate = "client");
dataservice::DataClient connect(const dataservice::ClientOptions& options);
// A gRPC channel of its own (no shared subchannel) with the "client"
// certificate, for tests that speak the protocol directly.
std::shared_ptr<grpc::Channel> rawChannel(const dataservice::DataServer& server);
std::unique_ptr<crackvis::v1::DataService::Stub> rawStub(const dataservice::DataServer& server);

// A Fetch of big.h5 that has read its first chunk: it holds one of the
// server's stream slots until it is cancelled, at the latest when it goes
// (without Finish).
class HeldFetch {
 public:
  explicit HeldFetch(crackvis::v1::DataService::Stub& stub);
  HeldFetch(const HeldFetch&) = delete;
  HeldFetch& operator=(const HeldFetch&) = delete;
  ~HeldFetch() { cancel(); }
  bool readMore() { return m_reader->Read(&m_chunk); }
  void cancel() { m_context.TryCancel(); }
  // Reads what is left and ends the call.
  grpc::Status finish() {
    while (readMore()) {
    }
    return m_reader->Finish();
  }

 private:
  grpc::ClientContext m_context;
  std::unique_ptr<grpc::ClientReader<crackvis::v1::FetchChunk>> m_reader;
  crackvis::v1::FetchChunk m_chunk;
};

// The server still answers: a health check and a valid read with a good
// client, bit-identical to the file. Fails the test otherwise.
void requireServerHealthy(const dataservice::DataServer& server);

// A hostile file: a chain of `levels` nested groups /g/g/g/... with a
// dataset at the bottom (deeper than Describe's depth limit from 65 on;
// before the walk opened objects by address, every lookup walked the whole
// path and describing it unbounded cost levels^2).
void writeNestedGroups(const std::string& path, int levels);
// A file of `count` empty sibling groups under the root: a Describe walks
// all of them (40,000 take about 0.6 s).
void writeWideGroups(const std::string& path, int count);

// Reads a whole dataset straight from a file (holding the HDF5 lock).
template <typename T>
std::vector<T> readDirect(const std::string& file, const std::string& dataset);
std::vector<std::byte> fileBytes(const std::string& path);

// Equal bit for bit (== on doubles would call -0.0 and 0.0 equal).
template <typename T>
bool bitIdentical(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace crackvis::testing
