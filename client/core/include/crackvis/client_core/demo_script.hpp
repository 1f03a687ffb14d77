// The scripted session of the one-command demo, for machines without a
// display: it drives a RenderClient like a user would (rotate the specimen,
// step through the fracture, switch between the four crack methods),
// records the received stream to MP4 and takes a full-resolution snapshot.
// It runs Qt's event loop while it waits, so it needs a Q(Core)Application.
#pragma once

#include <QString>
#include <functional>

#include <crackvis/client_core/render_client.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>

namespace crackvis::client {

struct DemoOptions {
  QString file = QStringLiteral("cuboidA.h5");
  pipeline::PipelineDescription view;  // its file is replaced by `file`
  QString moviePath = QStringLiteral("demo.mp4");
  QString picturePath = QStringLiteral("demo.png");
  int rotateEvents = 60;         // a half turn in small drags
  int stepStride = 20;           // steps shown on the way through the fracture
  double timeoutSeconds = 60.0;  // for each frame awaited
};

struct DemoResult {
  qint64 framesRecorded = 0;
  int framesShown = 0;
};

// Prints one line per stage through `say`.
Result<DemoResult> runDemo(RenderClient& client, const DemoOptions& options,
                           const std::function<void(const QString&)>& say);

}  // namespace crackvis::client
