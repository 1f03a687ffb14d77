// A small specimen with a through crack (a 5x5x5-site FCC block cut in the
// middle by cell cut), drawn as the default pipeline draws a step: particles
// as sphere impostors, the crack surface, the scalar bar. crackvis-render
// draws it once at start-up, so that a driver that makes a context but
// cannot draw fails there, and the driver's shader compiler and the scene's
// shaders are loaded before the first user waits for them.
#pragma once

#include <crackvis/render/scene_renderer.hpp>

namespace crackvis::render {

Status renderProbeScene(SceneRenderer& renderer, int width, int height, Image& out);

}  // namespace crackvis::render
