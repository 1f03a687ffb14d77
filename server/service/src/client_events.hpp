// A stream's ClientEvent as a SessionEvent: the one place where the render
// service's protocol meets the session (checkEvent, in session_event.hpp,
// then checks what the event asks for). Private to the service library;
// the render_events fuzz target compiles it too.
#pragma once

#include "crackvis/v1/render.pb.h"
#include <crackvis/common/status.hpp>
#include <crackvis/service/session_event.hpp>

namespace crackvis::service {

// INVALID_ARGUMENT for an unknown camera kind, an attach after the first
// message, or no event at all.
Result<SessionEvent> toSessionEvent(const crackvis::v1::ClientEvent& in);

}  // namespace crackvis::service
