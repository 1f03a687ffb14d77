// crackvis-client's window: a file browser (the data root through the render
// server, with each file's description), the pipeline panel, the viewport,
// a time bar (step slider, play/pause, fps), a status bar (fps, event-to-
// frame latency, bitrate), screenshots of any size (server Snapshot), MP4
// recording of the stream or of full-resolution frames re-rendered on the
// server, and views saved and loaded as pipeline descriptions (file, step,
// camera, size and everything the panel sets: what `crackvis snapshot` and
// `crackvis movie` take). Server errors become messages in the status bar
// and the log pane (a repeated one folded into a count), never a crash.
// ConnectDialog asks for the address, certificates and token and remembers
// them (QSettings).
#pragma once

#include <QDialog>
#include <QElapsedTimer>
#include <QMainWindow>
#include <QSize>
#include <QTimer>
#include <cstdint>

#include <crackvis/client_core/render_client.hpp>
#include <crackvis/client_ui/pipeline_panel.hpp>
#include <crackvis/client_ui/step_plot.hpp>
#include <crackvis/client_ui/viewport.hpp>

class QAction;
class QComboBox;
class QLabel;
class QLineEdit;
class QPlainTextEdit;
class QPushButton;
class QSlider;
class QDoubleSpinBox;
class QTreeWidget;

namespace crackvis::client {

class ConnectDialog : public QDialog {
  Q_OBJECT

 public:
  explicit ConnectDialog(QWidget* parent = nullptr);
  ConnectionSettings settings() const;
  void remember() const;  // QSettings

 private:
  QLineEdit* m_address;
  QLineEdit* m_ca;
  QLineEdit* m_cert;
  QLineEdit* m_key;
  QLineEdit* m_token;
};

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  RenderClient& client() { return m_client; }
  Viewport& viewport() { return *m_viewport; }
  PipelinePanel& pipelinePanel() { return *m_panel; }
  QTreeWidget& fileTree() { return *m_files; }
  QSlider& stepSlider() { return *m_slider; }
  // A live file's "Follow latest" and its "live: last step N s ago" / "run ended".
  QPushButton& followButton() { return *m_follow; }
  QLabel& liveLabel() { return *m_live; }
  StepPlot& stepPlot() { return *m_plot; }
  // The step scalar drawn beside the broken bonds ("none" and the file's).
  QComboBox& plotScalarBox() { return *m_plotScalar; }
  // What the Steps plot is drawn against ("step", "time", any series).
  QComboBox& plotAxisBox() { return *m_plotAxis; }
  // Adds the crack's numbers per step (the panel's method) to the plot.
  QPushButton& crackNumbersButton() { return *m_crackNumbers; }
  QString lastMessage() const { return m_lastMessage; }
  // Everything reported so far, one message a line (the messages pane).
  QString messages() const;

 public slots:
  // Connects, lists the files; false (and a message) on failure.
  bool connectTo(const crackvis::client::ConnectionSettings& settings);
  // Opens a session on `file` with the panel's description at its last
  // step; false (and a message) on failure.
  bool openFile(const QString& file);
  // The same at `step` (-1: the last): a step the file lacks is the
  // server's OUT_OF_RANGE, reported, not replaced by another step. A file
  // opens with the camera fitted to it, whatever the previous one showed.
  bool openFile(const QString& file, std::int64_t step);
  // Opens the view's file at its step with its camera (none: fitted) and
  // shows its settings in the panel; false (and a message) on failure.
  bool openView(const pipeline::PipelineDescription& view);
  // A saved view (File > Open view): a pipeline description file.
  bool loadView(const QString& path);
  // The view as shown (server's state: step, camera, size) to `path`.
  bool saveView(const QString& path);
  void showConnectDialog();
  // A PNG rendered by the server at `size` (empty: the stream's size).
  void saveScreenshot(const QString& path = QString(), QSize size = QSize());
  // Starts or stops the recording of the received stream (remuxed).
  void toggleRecording(const QString& path = QString());
  // Steps first..last (stride) re-rendered on the server at full resolution
  // at `size` (empty: the stream's), encoded into the MP4 `path` with a
  // progress dialog; false (and a message) on failure or when cancelled.
  bool recordMovie(const QString& path, int first, int last, int stride, QSize size, int fps);

 private:
  void buildMenus();
  void showScreenshotDialog();
  void showMovieDialog();
  void openViewDialog();
  void saveViewDialog();
  QSize streamSize() const;  // the stream's frame size, else the viewport's
  QWidget* buildTimeBar();
  void describe(const QString& file);
  QWidget* buildStepDock();
  void showHistory(const QString& file);
  void historyReady(const QString& file, const QString& cracks, const StepHistory& history,
                    const QString& error);
  void addCrackNumbers();
  void report(const QString& message);
  void updateStatus();
  void noteStepCount(int steps);
  void updateLive();
  void togglePlay();

  RenderClient m_client;
  Viewport* m_viewport;
  PipelinePanel* m_panel;
  QTreeWidget* m_files;
  QPlainTextEdit* m_description;
  QPlainTextEdit* m_log;
  QSlider* m_slider;
  StepPlot* m_plot;
  QComboBox* m_plotScalar;
  QComboBox* m_plotAxis;
  QPushButton* m_crackNumbers;
  // The crack method whose numbers the Steps plot shows ("" none); kept for
  // the file's later reads (a live file), dropped when another file opens.
  QString m_historyCracks;
  bool m_reportCrackNumbers = false;  // say so when the asked-for crack numbers arrive
  QPushButton* m_play;
  QDoubleSpinBox* m_fps;
  QLabel* m_stepLabel;
  // A live file: "Follow latest", and how long ago its last step came.
  QPushButton* m_follow;
  QLabel* m_live;
  bool m_isLive = false;
  bool m_runEnded = false;
  int m_knownSteps = 0;
  QElapsedTimer m_sinceLastStep;
  QElapsedTimer m_sincePlot;  // the Steps plot is read again at most every 2 s
  QLabel* m_stats;
  QTimer m_statusTimer;
  QString m_file;
  QString m_lastMessage;
  int m_lastMessageRepeats = 0;  // further times it came, folded into one line
  QAction* m_recordAction = nullptr;
  QString m_lastCrackWarning;  // the cause of the server's last, reported once
};

}  // namespace crackvis::client
