#include <QAction>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QFile>
#include <QFileDialog>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QMenuBar>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QScrollArea>
#include <QSettings>
#include <QSlider>
#include <QSplitter>
#include <QStatusBar>
#include <QTreeWidget>
#include <QVBoxLayout>

#include <crackvis/client/main_window.hpp>

namespace crackvis::client {

ConnectDialog::ConnectDialog(QWidget* parent) : QDialog(parent) {
  setWindowTitle(tr("Connect to crackvis-render"));
  QSettings stored;
  const ConnectionSettings defaults;
  auto field = [&](const char* key, const QString& fallback) {
    return new QLineEdit(stored.value(QString::fromUtf8(key), fallback).toString());
  };
  m_address = field("connection/address", defaults.address);
  m_ca = field("connection/ca", defaults.caPath);
  m_cert = field("connection/cert", defaults.certPath);
  m_key = field("connection/key", defaults.keyPath);
  m_token = new QLineEdit;  // secrets are not stored
  m_token->setEchoMode(QLineEdit::Password);
  auto* form = new QFormLayout(this);
  form->addRow(tr("address (host:port)"), m_address);
  form->addRow(tr("CA certificate"), m_ca);
  form->addRow(tr("client certificate"), m_cert);
  form->addRow(tr("client key"), m_key);
  form->addRow(tr("token (optional)"), m_token);
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
  connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  form->addRow(buttons);
}

ConnectionSettings ConnectDialog::settings() const {
  return {m_address->text(), m_ca->text(), m_cert->text(), m_key->text(), m_token->text()};
}

void ConnectDialog::remember() const {
  QSettings stored;
  stored.setValue(QStringLiteral("connection/address"), m_address->text());
  stored.setValue(QStringLiteral("connection/ca"), m_ca->text());
  stored.setValue(QStringLiteral("connection/cert"), m_cert->text());
  stored.setValue(QStringLiteral("connection/key"), m_key->text());
}

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
  setWindowTitle(QStringLiteral("crackvis"));
  m_viewport = new Viewport(m_client);
  setCentralWidget(new QWidget);
  auto* central = new QVBoxLayout(centralWidget());
  central->setContentsMargins(0, 0, 0, 0);
  central->addWidget(m_viewport, 1);
  central->addWidget(buildTimeBar());

  m_files = new QTreeWidget;
  m_files->setHeaderLabels({tr("file"), tr("size")});
  m_files->header()->setSectionResizeMode(0, QHeaderView::Stretch);
  m_description = new QPlainTextEdit;
  m_description->setReadOnly(true);
  auto* browser = new QSplitter(Qt::Vertical);
  browser->addWidget(m_files);
  browser->addWidget(m_description);
  auto* filesDock = new QDockWidget(tr("Data"), this);
  filesDock->setWidget(browser);
  addDockWidget(Qt::LeftDockWidgetArea, filesDock);

  m_panel = new PipelinePanel;
  auto* scroll = new QScrollArea;
  scroll->setWidget(m_panel);
  scroll->setWidgetResizable(true);
  auto* panelDock = new QDockWidget(tr("Pipeline"), this);
  panelDock->setWidget(scroll);
  addDockWidget(Qt::RightDockWidgetArea, panelDock);

  m_log = new QPlainTextEdit;
  m_log->setReadOnly(true);
  m_log->setMaximumBlockCount(500);
  auto* logDock = new QDockWidget(tr("Messages"), this);
  logDock->setWidget(m_log);
  addDockWidget(Qt::BottomDockWidgetArea, logDock);

  m_stats = new QLabel;
  statusBar()->addPermanentWidget(m_stats);
  buildMenus();

  connect(&m_client, &RenderClient::frameReady, m_viewport, &Viewport::showFrame);
  connect(&m_client, &RenderClient::stateChanged, this, [this](int step, int steps, bool playing) {
    const QSignalBlocker blocker(m_slider);
    m_slider->setRange(0, std::max(0, steps - 1));
    m_slider->setValue(step);
    m_stepLabel->setText(tr("step %1 / %2").arg(step).arg(steps - 1));
    m_play->setText(playing ? tr("Pause") : tr("Play"));
  });
  connect(&m_client, &RenderClient::eventFailed, this,
          [this](quint64, const QString& message) { report(message); });
  // A crack method that maps few broken bonds to faces says so in the status
  // bar and the messages pane, once per cause (the numbers change with every
  // step; the cause follows the first ": ").
  connect(&m_client, &RenderClient::crackMappingChanged, this,
          [this](double, const QString& warning) {
            const QString cause = warning.section(QStringLiteral(": "), 1);
            if (!warning.isEmpty() && cause != m_lastCrackWarning) {
              report(tr("warning: %1").arg(warning));
            }
            m_lastCrackWarning = cause;
          });
  connect(&m_client, &RenderClient::connectionLost, this, [this](const QString& why) {
    report(tr("connection lost (%1); reconnecting").arg(why));
  });
  connect(&m_client, &RenderClient::reconnected, this, [this] { report(tr("reconnected")); });
  connect(m_files, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item) {
    if (item != nullptr) {
      describe(item->data(0, Qt::UserRole).toString());
    }
  });
  connect(m_files, &QTreeWidget::itemActivated, this,
          [this](QTreeWidgetItem* item) { openFile(item->data(0, Qt::UserRole).toString()); });
  connect(m_panel, &PipelinePanel::changed, this, [this](const pipeline::PipelineDescription& d) {
    if (m_client.hasSession()) {
      auto next = d;
      next.file = m_file.toStdString();
      next.step = m_client.step();
      next.view.width = m_viewport->width() & ~1;
      next.view.height = m_viewport->height() & ~1;
      m_client.replacePipeline(QString::fromStdString(pipeline::toXml(next)));
    }
  });
  connect(m_viewport, &Viewport::playToggled, this, &MainWindow::togglePlay);
  connect(m_viewport, &Viewport::stepBy, this,
          [this](int delta) { m_slider->setValue(m_slider->value() + delta); });
  m_statusTimer.setInterval(500);
  connect(&m_statusTimer, &QTimer::timeout, this, &MainWindow::updateStatus);
  m_statusTimer.start();
  resize(1400, 860);
}

MainWindow::~MainWindow() {
  m_client.closeSession();
}

QWidget* MainWindow::buildTimeBar() {
  auto* bar = new QWidget;
  auto* layout = new QHBoxLayout(bar);
  m_play = new QPushButton(tr("Play"));
  m_slider = new QSlider(Qt::Horizontal);
  m_slider->setObjectName(QStringLiteral("step"));
  m_fps = new QDoubleSpinBox;
  m_fps->setRange(0.5, 60.0);
  m_fps->setValue(10.0);
  m_fps->setSuffix(tr(" steps/s"));
  m_stepLabel = new QLabel(tr("no session"));
  layout->addWidget(m_play);
  layout->addWidget(m_slider, 1);
  layout->addWidget(m_stepLabel);
  layout->addWidget(m_fps);
  connect(m_play, &QPushButton::clicked, this, &MainWindow::togglePlay);
  connect(m_slider, &QSlider::valueChanged, this, [this](int step) {
    if (m_client.hasSession()) {
      m_client.setStep(step);
      m_stepLabel->setText(tr("step %1 / %2").arg(step).arg(m_client.stepCount() - 1));
    }
  });
  return bar;
}

void MainWindow::buildMenus() {
  auto* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("&Connect..."), this, &MainWindow::showConnectDialog);
  file->addAction(tr("&Screenshot (full resolution)..."), this, [this] { saveScreenshot(); });
  file->addAction(tr("&Record to MP4..."), this, [this] { toggleRecording(); });
  file->addSeparator();
  file->addAction(tr("&Quit"), this, &QWidget::close);
  auto* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Reset camera (r)"), this, [this] { m_client.resetCamera(); });
  view->addAction(tr("&Play / pause (space)"), this, &MainWindow::togglePlay);
}

QString MainWindow::messages() const {
  return m_log->toPlainText();
}

void MainWindow::report(const QString& message) {
  m_lastMessage = message;
  statusBar()->showMessage(message, 10000);
  m_log->appendPlainText(message);
}

bool MainWindow::connectTo(const ConnectionSettings& settings) {
  if (Status status = m_client.connectTo(settings); !status) {
    report(tr("cannot connect: %1").arg(QString::fromStdString(status.message())));
    return false;
  }
  auto files = m_client.listFiles();
  if (!files) {
    report(QString::fromStdString(files.status().message()));
    return false;
  }
  m_files->clear();
  for (const FileEntry& entry : *files) {
    auto* item = new QTreeWidgetItem(
        m_files, {entry.path, QStringLiteral("%1 MB").arg(entry.sizeBytes / 1e6, 0, 'f', 1)});
    item->setData(0, Qt::UserRole, entry.path);
    item->setDisabled(!entry.isHdf5);
  }
  report(tr("connected to %1: %2 files").arg(settings.address).arg(files->size()));
  return true;
}

void MainWindow::describe(const QString& file) {
  auto summary = m_client.describe(file);
  if (!summary) {
    m_description->setPlainText(QString::fromStdString(summary.status().message()));
    return;
  }
  QString text =
      tr("%1\nformat %2, %3 MB\nN = %4 particles, M = %5 bonds\n%6 steps, t = %7 .. %8 s\n\n")
          .arg(summary->file,
               summary->format.isEmpty() ? tr("(not crackvis-dem)") : summary->format)
          .arg(summary->sizeBytes / 1e6, 0, 'f', 1)
          .arg(summary->particles)
          .arg(summary->bonds)
          .arg(summary->steps)
          .arg(summary->firstTime)
          .arg(summary->lastTime);
  text += summary->arrays.join(QLatin1Char('\n'));
  m_description->setPlainText(text);
  m_panel->setExtras(summary->particleExtras, summary->bondExtras);
}

bool MainWindow::openFile(const QString& file) {
  describe(file);  // the file's extra arrays for the colour-by list
  auto d = m_panel->description();
  // An extra array of the previous file that this one lacks: back to the default.
  const QString prefix = QStringLiteral("extra: ");
  if (d.particles.colourBy == pipeline::ParticleColourBy::kExtra &&
      m_panel->particleColourBox()->findText(
          prefix + QString::fromStdString(d.particles.colourByExtra)) < 0) {
    d.particles.colourBy = pipeline::ParticleColourBy::kSolid;
    d.particles.colourByExtra.clear();
  }
  if (d.bonds.colourBy == pipeline::BondColourBy::kExtra &&
      m_panel->bondColourBox()->findText(prefix + QString::fromStdString(d.bonds.colourByExtra)) <
          0) {
    d.bonds.colourBy = pipeline::BondColourBy::kState;
    d.bonds.colourByExtra.clear();
  }
  d.file = file.toStdString();
  d.step = -1;
  d.view.width = std::max(16, m_viewport->width() & ~1);
  d.view.height = std::max(16, m_viewport->height() & ~1);
  if (Status status = m_client.openSession(QString::fromStdString(pipeline::toXml(d))); !status) {
    report(tr("cannot open %1: %2").arg(file, QString::fromStdString(status.message())));
    return false;
  }
  m_file = file;
  const QSignalBlocker blocker(m_slider);
  m_slider->setRange(0, std::max(0, m_client.stepCount() - 1));
  m_slider->setValue(m_client.stepCount() - 1);
  m_stepLabel->setText(tr("step %1 / %2").arg(m_slider->value()).arg(m_client.stepCount() - 1));
  setWindowTitle(tr("crackvis - %1").arg(file));
  report(tr("opened %1 (%2 steps)").arg(file).arg(m_client.stepCount()));
  m_viewport->setFocus();
  return true;
}

void MainWindow::showConnectDialog() {
  ConnectDialog dialog(this);
  if (dialog.exec() == QDialog::Accepted && connectTo(dialog.settings())) {
    dialog.remember();
  }
}

void MainWindow::saveScreenshot(const QString& given) {
  const QString path =
      given.isEmpty() ? QFileDialog::getSaveFileName(this, tr("Screenshot"),
                                                     QStringLiteral("view.png"), tr("PNG (*.png)"))
                      : given;
  if (path.isEmpty()) {
    return;
  }
  auto png = m_client.snapshotPng();
  if (!png) {
    report(QString::fromStdString(png.status().message()));
    return;
  }
  QFile out(path);
  if (!out.open(QIODevice::WriteOnly) || out.write(*png) != png->size()) {
    report(tr("cannot write %1: %2").arg(path, out.errorString()));
    return;
  }
  report(tr("wrote %1").arg(path));
}

void MainWindow::toggleRecording(const QString& given) {
  if (m_client.recording()) {
    const Status status = m_client.stopRecording();
    report(status ? tr("recording stopped") : QString::fromStdString(status.message()));
    return;
  }
  const QString path = given.isEmpty()
                           ? QFileDialog::getSaveFileName(
                                 this, tr("Record"), QStringLiteral("view.mp4"), tr("MP4 (*.mp4)"))
                           : given;
  if (path.isEmpty()) {
    return;
  }
  const Status status = m_client.startRecording(path);
  report(status ? tr("recording to %1").arg(path) : QString::fromStdString(status.message()));
}

void MainWindow::togglePlay() {
  if (m_client.hasSession()) {
    m_client.play(!m_client.playing(), m_fps->value());
  }
}

void MainWindow::updateStatus() {
  const StreamStatistics stats = m_client.statistics();
  m_stats->setText(tr("%1 fps   latency %2 ms   %3 Mbit/s%4")
                       .arg(stats.fps, 0, 'f', 0)
                       .arg(stats.latencyMs, 0, 'f', 0)
                       .arg(stats.bitrateBps / 1e6, 0, 'f', 2)
                       .arg(m_client.recording() ? tr("   REC") : QString()));
}

}  // namespace crackvis::client
