// Private to server/render: the VTK actors SceneRenderer::setScene puts in
// its renderer for a description's layers (particles, cracks with their marks
// and intact faces, the local decomposition's edges, bonds). Each coloured
// layer appends its legend to `legends` (when not null) for the overlays.
#pragma once

#include <span>
#include <vector>

#include <vtkActor.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>

#include "overlays.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/scene_renderer.hpp>

namespace crackvis::render::detail {

// The particles' mean radius; 1 without particles.
double meanRadius(std::span<const double> radius);

// The impostors' radius array (their mapper's scale array).
inline constexpr const char* kSphereRadiusArray = "sphere_radius";

vtkSmartPointer<vtkActor> particleActor(const pipeline::PipelineDescription& d,
                                        const SceneInput& input, std::vector<Legend>* legends);
// Returns the crack primitives' actor (not their marks' or intact faces').
vtkActor* addCracks(const pipeline::PipelineDescription& d, const SceneInput& input,
                    vtkRenderer* renderer, std::vector<Legend>* legends);
void addDecompositionEdges(const SceneInput& input, vtkRenderer* renderer);
void addBonds(const pipeline::PipelineDescription& d, const SceneInput& input,
              vtkRenderer* renderer, std::vector<Legend>* legends);

}  // namespace crackvis::render::detail
