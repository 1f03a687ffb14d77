// Edits every element of a pipeline description (pipeline-schemas/
// pipeline.xsd): crack method and validation, colour-bys with their colour
// ranges (per step, over the series, or set), representations, opacities,
// one clipping plane for any of the three layers, a threshold on any of a
// layer's quantities, bonds, decomposition and inconsistency marks,
// background, colour map, scalar bar, annotations, stream rate. What it emits is a typed
// description; crackvis::pipeline::toXml turns it into a valid document.
#pragma once

#include <QWidget>

#include <crackvis/pipeline/pipeline_description.hpp>

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QSpinBox;
class QLineEdit;

namespace crackvis::client {

class PipelinePanel : public QWidget {
  Q_OBJECT

 public:
  explicit PipelinePanel(QWidget* parent = nullptr);

  const pipeline::PipelineDescription& description() const { return m_description; }
  // Shows a description without emitting changed().
  void setDescription(const pipeline::PipelineDescription& description);
  QComboBox* methodBox() const { return m_method; }
  // The file's per-particle and per-bond extra arrays, offered as
  // "extra: NAME" under colour by (replacing the previous file's).
  void setExtras(const QStringList& particleNames, const QStringList& bondNames);
  QComboBox* particleColourBox() const { return m_particleColour; }
  QComboBox* bondColourBox() const { return m_bondColour; }

  // A coloured layer's range editor, its switch for the clipping plane and
  // its threshold: the same controls for particles, cracks and bonds. An
  // empty bound is open (the threshold) or left to the data (the range).
  struct LayerControls {
    QComboBox* rangeMode = nullptr;  // per step, over the series, set
    QLineEdit* rangeMin = nullptr;
    QLineEdit* rangeMax = nullptr;
    QCheckBox* clip = nullptr;  // the panel's plane cuts this layer
    QCheckBox* threshold = nullptr;
    QComboBox* thresholdBy = nullptr;  // the layer's colour-by quantities but solid
    QLineEdit* thresholdMin = nullptr;
    QLineEdit* thresholdMax = nullptr;
  };
  const LayerControls& particleControls() const { return m_particleLayer; }
  const LayerControls& crackControls() const { return m_crackLayer; }
  const LayerControls& bondControls() const { return m_bondLayer; }
  QDoubleSpinBox* clipOrigin(int axis) const { return m_clipOrigin[axis]; }
  QDoubleSpinBox* clipNormal(int axis) const { return m_clipNormal[axis]; }

 signals:
  void changed(const crackvis::pipeline::PipelineDescription& description);

 private:
  void collect();  // widgets -> m_description, then changed()
  void show(const pipeline::PipelineDescription& d);

  pipeline::PipelineDescription m_description;
  bool m_updating = false;
  QCheckBox* m_particlesVisible;
  QComboBox* m_particleRepresentation;
  QComboBox* m_particleColour;
  QDoubleSpinBox* m_particleOpacity;
  LayerControls m_particleLayer;
  LayerControls m_crackLayer;
  LayerControls m_bondLayer;
  QDoubleSpinBox* m_clipOrigin[3];
  QDoubleSpinBox* m_clipNormal[3];
  QCheckBox* m_cracksVisible;
  QComboBox* m_method;
  QCheckBox* m_validation;
  QDoubleSpinBox* m_tolerance;
  QCheckBox* m_merge;
  QComboBox* m_decompositionKind;
  QSpinBox* m_largest;
  QComboBox* m_crackColour;
  QDoubleSpinBox* m_crackOpacity;
  QComboBox* m_bondsShow;
  QComboBox* m_bondRepresentation;
  QComboBox* m_bondColour;
  QDoubleSpinBox* m_tubeRadius;
  QCheckBox* m_decomposition;
  QCheckBox* m_inconsistent;
  QLineEdit* m_background;
  QComboBox* m_colourMap;
  QCheckBox* m_scalarBar;
  QCheckBox* m_annotations;
  QSpinBox* m_fps;
  QSpinBox* m_bitrate;
};

}  // namespace crackvis::client
