// The thin client's core (no widgets): a connection to crackvis-render with
// mutual TLS and an optional token, ListFiles/Describe, and one session at a
// time with its stream. Networking and decoding run on their own threads:
// a reader takes the server's messages, a decoder thread turns H.264 access
// units into QImages (libavcodec), a writer sends the events, so the GUI
// thread never blocks on the network. Frames arrive through frameReady
// (queued to the receiver's thread). When the stream breaks, the client
// reconnects with backoff: it re-attaches to its session (asking for a
// keyframe) or, if the server lost it (a restart), opens a new one with the
// same pipeline and step.
#pragma once

#include <QImage>
#include <QObject>
#include <QSize>
#include <QString>
#include <QStringList>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <crackvis/common/certificates.hpp>
#include <crackvis/common/status.hpp>

namespace crackvis::client {

// The defaults: certs/generated/ (a source checkout's development
// certificates), or where those are missing /etc/crackvis/certs.
struct ConnectionSettings {
  QString address = QStringLiteral("localhost:50052");
  QString caPath = QString::fromStdString(defaultCertificatePath("ca.pem"));
  QString certPath = QString::fromStdString(defaultCertificatePath("client.pem"));
  QString keyPath = QString::fromStdString(defaultCertificatePath("client.key"));
  QString token;  // sent as "authorization: Bearer <token>" when set
};

struct FileEntry {
  QString path;
  qint64 sizeBytes = 0;
  bool isHdf5 = false;
};

// What the file browser shows of a file.
struct FileSummary {
  QString file;
  QString format;  // "crackvis-dem" for DEM results
  qint64 sizeBytes = 0;
  qint64 particles = 0;
  qint64 bonds = 0;
  int steps = 0;
  double firstTime = 0.0;
  double lastTime = 0.0;
  QStringList arrays;  // "/particles/radius float64 [46875]", ...
  // Per-particle extra arrays a view can colour by (crackvis-dem v1.1
  // extra/particles/NAME, constant or per step).
  QStringList particleExtras;
  QStringList bondExtras;  // likewise extra/bonds/NAME
};

// A file's course over its steps (RenderService.StepHistory), for the
// client's step plot.
struct StepHistory {
  std::vector<double> time;         // per step, s
  std::vector<qint64> brokenBonds;  // broken at or before each step
  qint64 bondCount = 0;
  QStringList scalarNames;                   // the file's step scalars (and crack numbers)
  std::vector<std::vector<double>> scalars;  // [scalar][step], NaN where a step lacks it
};

struct FrameInfo {
  quint64 frameId = 0;
  quint64 lastEventId = 0;
  int step = 0;
  bool keyframe = false;
  bool fullResolution = true;
  int reduction = 1;
  double renderMs = 0.0;
  double encodeMs = 0.0;
  double latencyMs = -1.0;  // event to decoded frame, when it reflects a new event
  double decodeMs = 0.0;    // this client's decode of the frame and its conversion to a QImage
  // The server's part of the latency (FrameTimings.event_to_send_ms: the
  // last event it reflects received to the frame sent); 0 when it reflects
  // no new event.
  double serverEventToSendMs = 0.0;
  // When each event that this frame is the first to reflect was sent: the
  // viewport times them to the frame's paint (Viewport::painted).
  std::vector<std::chrono::steady_clock::time_point> eventsSentAt;
};

struct StreamStatistics {
  double fps = 0.0;         // decoded frames in the last second
  double bitrateBps = 0.0;  // received bits in the last second
  double latencyMs = 0.0;   // median event-to-frame latency of the last 30 events
  quint64 framesDecoded = 0;
  quint64 reconnects = 0;
};

class RenderClient : public QObject {
  Q_OBJECT

 public:
  explicit RenderClient(QObject* parent = nullptr);
  ~RenderClient() override;

  // Checks the address (HOST:PORT), reads the TLS files and lists the
  // server's files (one round trip); a failure says what to do
  // (crackvis/rpc/connection_advice.hpp: not running, not a crackvis-render,
  // plaintext).
  Status connectTo(const ConnectionSettings& settings);
  bool connected() const;
  const ConnectionSettings& settings() const;

  Result<std::vector<FileEntry>> listFiles();
  Result<FileSummary> describe(const QString& file);
  // The file's course over its steps, asked for off the calling thread: the
  // answer comes as stepHistoryReady, on the client's thread. With a crack
  // method ("local-voronoi", ...), the scalars gain the crack's numbers per
  // step (crack area, front, fragments, modes): the server runs the method
  // over every step, seconds for a large file, and the window stays
  // responsive meanwhile. One call runs at a time; a request made meanwhile
  // waits for it, and only the newest waiting one is kept.
  void requestStepHistory(const QString& file, const QString& cracks = {});

  // Opens a session with a pipeline description and attaches its stream.
  Status openSession(const QString& pipelineXml);
  void closeSession();
  bool hasSession() const;
  int stepCount() const;
  int step() const;
  bool playing() const;
  QString pipelineXml() const;

  // Events: queued for the writer thread; each returns its event id.
  // `still`: a camera move that is not part of a drag (a scripted view),
  // answered at once by a full-resolution frame (CameraEvent.still).
  quint64 rotate(double dx, double dy, bool still = false);
  quint64 pan(double dx, double dy);
  quint64 zoom(double amount);
  quint64 resetCamera();
  quint64 setStep(int step);
  // Follow a live file: its newest step now and each new one as it comes
  // (any setStep or play ends following).
  quint64 follow();
  quint64 play(bool playing, double fps = 0.0);
  quint64 resize(int width, int height);
  quint64 replacePipeline(const QString& xml);
  quint64 requestStill();
  // What is drawn at (x, y), fractions of the view from its top-left
  // corner; the answer comes through picked().
  quint64 pick(double x, double y);

  // A full-resolution PNG of the session (blocking: one call), at any size
  // the server allows (0: the stream's). With `step` the session moves to
  // that step first (-1: the last) and stays there.
  Result<QByteArray> snapshotPng(int width = 0, int height = 0,
                                 std::optional<int> step = std::nullopt);

  // A movie of full-resolution frames re-rendered on the server (a Snapshot
  // at each of `steps`, width x height, even), encoded here with libx264 at
  // constant quality: unlike a recording of the stream, no frame is a
  // reduced interactive one. `progress(done, total)` after each frame;
  // returning false stops it (CANCELLED, the file removed). The session is
  // left at the last step.
  Status recordMovie(const QString& path, const std::vector<int>& steps, int width, int height,
                     int fps, const std::function<bool(int, int)>& progress = {});
  // The stream's frame size (0 x 0 before the first frame).
  QSize frameSize() const;

  // Recording of the received stream to MP4 (remuxed, not re-encoded).
  Status startRecording(const QString& path);
  Status stopRecording();
  bool recording() const;
  // Frames the last finished recording holds.
  qint64 recordedFrames() const;

  StreamStatistics statistics() const;

 signals:
  void frameReady(const QImage& image, const crackvis::client::FrameInfo& info);
  void stateChanged(int step, int stepCount, bool playing);
  // A live file (its writer has it open: steps keep coming), whether the
  // session follows its newest step, and whether the writer closed it.
  void liveChanged(bool live, bool following, bool runEnded);
  // The shown step's broken bonds that became crack surface elements, and
  // the server's warning when fewer than 95 % did (empty otherwise).
  void crackMappingChanged(double mappedFraction, const QString& warning);
  void eventFailed(quint64 eventId, const QString& message);
  // The answer to pick(): "particle 120 at (...) m: radius ..., damage ..."
  // (or "nothing there"), the kind ("particle", "crack element" or empty)
  // and the particle's or element's index.
  void picked(quint64 eventId, const QString& text, const QString& kind, qint64 index);
  void connectionLost(const QString& why);
  void reconnected();
  // requestStepHistory's answer: `error` empty when `history` holds it.
  void stepHistoryReady(const QString& file, const QString& cracks,
                        const crackvis::client::StepHistory& history, const QString& error);

 private:
  void startStepHistory(const QString& file, const QString& cracks);
  void finishStepHistory(const QString& file, const QString& cracks, const QString& error,
                         const StepHistory& history);

  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace crackvis::client

Q_DECLARE_METATYPE(crackvis::client::FrameInfo)
