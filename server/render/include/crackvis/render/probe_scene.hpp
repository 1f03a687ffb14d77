// A small specimen with a through crack (a 5x5x5-site FCC block cut in the
// middle), drawn as a pipeline description draws a step: particles as sphere
// impostors, the crack surface, the bonds and the overlays it asks for.
// crackvis-render draws it once at start-up, with the default description,
// so that a driver that makes a context but cannot draw fails there and the
// driver's shader compiler is loaded before the first user waits for it.
// Each session rehearses its own description on it while its file opens, so
// that its first frame finds the shader programs of its context made.
#pragma once

#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/scene_renderer.hpp>

namespace crackvis::render {

// The default description at width x height.
Status renderProbeScene(SceneRenderer& renderer, int width, int height, Image& out);

// SceneRenderer::rehearse on the probe specimen with `description`'s layers
// and view (its crack method included; its file and step are ignored). Every
// colour-by finds its array: the extra arrays and velocities are zeros, the
// reference positions the current ones.
Status rehearseOnProbe(SceneRenderer& renderer, const pipeline::PipelineDescription& description);

}  // namespace crackvis::render
