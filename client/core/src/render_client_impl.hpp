// RenderClient's private state (RenderClient::Impl), shared by the files
// that implement the client: render_client.cpp (construction, the channel,
// its authorization and unary calls), session_stream.cpp (a session and its
// stream: the reader, writer and decoder threads, events, reconnects,
// statistics) and recording.cpp (snapshots, movies, recording the stream).
// Private to the client core library.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>

#include <grpcpp/grpcpp.h>

#include "crackvis/v1/render.grpc.pb.h"
#include <crackvis/client_core/render_client.hpp>
#include <crackvis/common/status.hpp>
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/record/stream_recorder.hpp>
#include <crackvis/rpc/connection_advice.hpp>

namespace crackvis::client {

namespace v1 = crackvis::v1;
using Clock = std::chrono::steady_clock;

struct EncodedUnit {
  encode::EncodedFrame frame;
  FrameInfo info;
  std::uint64_t generation = 0;  // the stream it came from: a new one starts a new decoder
  Clock::time_point received;
};

struct RenderClient::Impl {
  RenderClient* owner = nullptr;
  ConnectionSettings settings;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::RenderService::Stub> stub;

  // Session state, under `mutex`.
  mutable std::mutex mutex;
  std::string sessionId;
  std::string pipelineXml;
  int stepCount = 0;
  int step = 0;
  bool playing = false;

  // Events for the writer, under `mutex`.
  std::condition_variable eventsChanged;
  std::deque<v1::ClientEvent> events;
  std::uint64_t nextEventId = 1;
  std::map<std::uint64_t, Clock::time_point> sentAt;

  // The stream currently attached, under `mutex`.
  grpc::ClientContext* streamContext = nullptr;
  std::uint64_t streamGeneration = 0;  // counts attached streams

  // Frames for the decoder, under `mutex`.
  std::condition_variable unitsChanged;
  std::deque<EncodedUnit> units;

  // The newest decoded frame for the GUI thread (older ones are dropped).
  std::mutex deliveryMutex;
  std::optional<std::pair<QImage, FrameInfo>> latest;
  bool deliveryPending = false;

  // Statistics, under `mutex`.
  std::deque<Clock::time_point> frameTimes;
  std::deque<std::pair<Clock::time_point, std::size_t>> byteTimes;
  std::deque<double> latencies;
  quint64 framesDecoded = 0;
  quint64 reconnects = 0;

  std::unique_ptr<record::StreamRecorder> recorder;  // under `mutex`
  Clock::time_point recordingStart;
  qint64 recordedFrames = 0;
  int frameWidth = 0;  // of the stream's pictures, under `mutex`
  int frameHeight = 0;

  std::atomic<bool> stopping{false};
  std::thread supervisor;
  std::thread decoder;

  // requestStepHistory's call in flight (GUI thread only), with its own
  // context to cancel it when the client goes, and the newest request that
  // waits for it.
  std::thread historyCall;
  std::shared_ptr<grpc::ClientContext> historyContext;
  std::optional<std::pair<QString, QString>> pendingHistory;

  // render_client.cpp: the connection.
  Status failure(const grpc::Status& status, const char* call) const;

  // One unary call of the connection's file calls: on a connected channel
  // (rpc::awaitConnection), authorized, its failure worded by
  // connection_advice. `call(context, response)` makes the call.
  template <typename Response, typename Call>
  Status unary(const char* name, Response& response, Call&& call) {
    if (!stub) {
      return failedPrecondition("not connected");
    }
    awaitConnection();
    grpc::ClientContext context;
    authorize(context);
    return failure(call(context, response), name);
  }

  void authorize(grpc::ClientContext& context) const;
  // Gives a channel that is not connected yet its connection first: gRPC
  // 1.51 can fail an attempt in progress (rpc::awaitConnection).
  void awaitConnection() const {
    rpc::awaitConnection(*channel, settings.address.toStdString(),
                         std::chrono::system_clock::now() + std::chrono::seconds(10));
  }

  // session_stream.cpp: the session and its stream.
  std::uint64_t queue(v1::ClientEvent event);
  Status openOnServer(const std::string& xml);
  // One attached stream: writes the attach message, runs the writer thread,
  // reads until the stream ends; returns how it ended.
  grpc::Status runStream(bool askKeyframe);
  void writeLoop(grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>& stream,
                 std::atomic<bool>& ended);
  void handle(const v1::ServerMessage& message, std::uint64_t generation);
  // Re-attaches (or re-opens) until it works or the client stops.
  void supervise();
  void decodeLoop();
  // Hands the newest frame to the GUI thread; frames it has not taken yet
  // are replaced (a slow GUI never falls behind the stream).
  void deliver(QImage image, const FrameInfo& info);
  void stopSession();

  // recording.cpp: recording the stream.
  // Under `mutex`: the received access unit into the MP4, if recording.
  void record(const EncodedUnit& unit);
};

}  // namespace crackvis::client
