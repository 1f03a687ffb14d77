// crackvis-client's window: a file browser (the data root through the render
// server, with each file's description), the pipeline panel, the viewport,
// a time bar (step slider, play/pause, fps), a status bar (fps, event-to-
// frame latency, bitrate), a full-resolution screenshot and MP4 recording.
// Server errors become messages in the status bar and the log pane, never a
// crash. ConnectDialog asks for the address, certificates and token and
// remembers them (QSettings).
#pragma once

#include <QDialog>
#include <QMainWindow>
#include <QTimer>

#include <crackvis/client/pipeline_panel.hpp>
#include <crackvis/client/render_client.hpp>
#include <crackvis/client/viewport.hpp>

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
  QString lastMessage() const { return m_lastMessage; }
  // Everything reported so far, one message a line (the messages pane).
  QString messages() const;

 public slots:
  // Connects, lists the files; false (and a message) on failure.
  bool connectTo(const crackvis::client::ConnectionSettings& settings);
  // Opens a session on `file` with the panel's description.
  bool openFile(const QString& file);
  void showConnectDialog();
  void saveScreenshot(const QString& path = QString());
  void toggleRecording(const QString& path = QString());

 private:
  void buildMenus();
  QWidget* buildTimeBar();
  void describe(const QString& file);
  void report(const QString& message);
  void updateStatus();
  void togglePlay();

  RenderClient m_client;
  Viewport* m_viewport;
  PipelinePanel* m_panel;
  QTreeWidget* m_files;
  QPlainTextEdit* m_description;
  QPlainTextEdit* m_log;
  QSlider* m_slider;
  QPushButton* m_play;
  QDoubleSpinBox* m_fps;
  QLabel* m_stepLabel;
  QLabel* m_stats;
  QTimer m_statusTimer;
  QString m_file;
  QString m_lastMessage;
  QString m_lastCrackWarning;  // the cause of the server's last, reported once
};

}  // namespace crackvis::client
