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
#include <QString>
#include <QStringList>
#include <cstdint>
#include <memory>
#include <vector>

#include <crackvis/common/status.hpp>

namespace crackvis::client {

struct ConnectionSettings {
  QString address = QStringLiteral("localhost:50052");
  QString caPath = QStringLiteral("certs/generated/ca.pem");
  QString certPath = QStringLiteral("certs/generated/client.pem");
  QString keyPath = QStringLiteral("certs/generated/client.key");
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

  // Reads the TLS files and checks the server's health (one round trip).
  Status connectTo(const ConnectionSettings& settings);
  bool connected() const;
  const ConnectionSettings& settings() const;

  Result<std::vector<FileEntry>> listFiles();
  Result<FileSummary> describe(const QString& file);

  // Opens a session with a pipeline description and attaches its stream.
  Status openSession(const QString& pipelineXml);
  void closeSession();
  bool hasSession() const;
  int stepCount() const;
  int step() const;
  bool playing() const;
  QString pipelineXml() const;

  // Events: queued for the writer thread; each returns its event id.
  quint64 rotate(double dx, double dy);
  quint64 pan(double dx, double dy);
  quint64 zoom(double amount);
  quint64 resetCamera();
  quint64 setStep(int step);
  quint64 play(bool playing, double fps = 0.0);
  quint64 resize(int width, int height);
  quint64 replacePipeline(const QString& xml);
  quint64 requestStill();

  // A full-resolution PNG of the session (blocking: one call).
  Result<QByteArray> snapshotPng(int width = 0, int height = 0);

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
  // The shown step's broken bonds that became crack surface elements, and
  // the server's warning when fewer than 95 % did (empty otherwise).
  void crackMappingChanged(double mappedFraction, const QString& warning);
  void eventFailed(quint64 eventId, const QString& message);
  void connectionLost(const QString& why);
  void reconnected();

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace crackvis::client

Q_DECLARE_METATYPE(crackvis::client::FrameInfo)
