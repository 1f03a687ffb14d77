// Camera moves in view units, so that a client's mouse deltas map the same
// way at any window size: dx, dy are fractions of the view's width and height,
// x to the right and y downwards (screen convention). A header of its own so
// that what describes an event needs no renderer.
#pragma once

namespace crackvis::render {

enum class CameraMove { kRotate, kPan, kZoom, kReset };

}  // namespace crackvis::render
