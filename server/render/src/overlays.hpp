// What a SceneRenderer writes over and beside the scene: one scalar bar per
// coloured layer (particles, cracks, bonds), stacked in a strip right of the
// scene so that no bar covers the specimen, and the annotations (step and
// time, crack method, axes triad, length scale bar). Built per scene, laid
// out per frame: frames of any size (reduced interactive ones, large
// snapshots) get fonts, the scale bar's length and the triad's turn of their own.
#pragma once

#include <mutex>
#include <string>
#include <vector>

#include <vtkActor2D.h>
#include <vtkAxesActor.h>
#include <vtkPolyData.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkScalarsToColors.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>

#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/scene_model/scene_content.hpp>

namespace crackvis::render {

// A coloured layer's lookup table (its range already set) and quantity.
struct Legend {
  vtkSmartPointer<vtkScalarsToColors> table;
  scene::Quantity quantity;
  scene::ValueRange range;
};

class Overlays {
 public:
  // Adds its renderers to `window`; `scene` is the renderer the specimen is
  // drawn in, whose viewport leaves room for the legend strip.
  Overlays(vtkRenderWindow* window, vtkRenderer* scene);
  void setScene(const pipeline::PipelineDescription& description, const scene::SceneInput& input,
                std::vector<Legend> legends);
  // Before each frame of width x height pixels.
  void layout(int width, int height);

  // The share of the width the legend strip takes (0 without bars).
  double stripFraction() const { return m_strip; }
  // Whether a frame draws text (bars, annotations).
  bool drawsText() const { return !m_bars.empty() || !m_texts.empty() || m_triad->GetDraw(); }
  // VTK's text rendering (vtkTextRenderer, vtkFreeTypeTools) is a process-wide
  // singleton with unguarded caches: sessions rendering text on their own
  // threads at once corrupt its heap. A frame that draws text holds this.
  static std::mutex& textMutex();

 private:
  void addScalarBars(const pipeline::PipelineDescription& description);
  void addAnnotations(const pipeline::PipelineDescription& description,
                      const scene::SceneInput& input);
  void layoutTriad(int width, int height);
  void layoutScaleBar(int sceneWidth, int height, int fontSize);

  vtkRenderer* m_scene;
  vtkSmartPointer<vtkRenderer> m_legends;  // the strip right of the scene
  vtkSmartPointer<vtkRenderer> m_triad;    // a corner of the scene, drawn over it
  vtkSmartPointer<vtkAxesActor> m_axes;
  std::vector<Legend> m_legendsShown;
  std::vector<vtkSmartPointer<vtkScalarBarActor>> m_bars;
  std::vector<vtkSmartPointer<vtkTextActor>> m_texts;  // top left, one per line
  vtkSmartPointer<vtkActor2D> m_scaleLine;
  vtkSmartPointer<vtkPolyData> m_scaleLineData;
  vtkSmartPointer<vtkTextActor> m_scaleText;
  double m_strip = 0.0;
  int m_laidOutWidth = 0;  // the frame size of the last layout: unchanged, nothing to redo
  int m_laidOutHeight = 0;
  double m_textLightness = 1.0;  // white on dark backgrounds, black on light
};

}  // namespace crackvis::render
