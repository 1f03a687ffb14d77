// Tells the service manager what a service is doing: systemd's readiness
// protocol (sd_notify(3)) spoken directly, a datagram to the socket named in
// $NOTIFY_SOCKET, so that a `Type=notify` unit counts as started only once
// the service accepts calls, and `systemctl start` returns when it does.
#pragma once

#include <string_view>

namespace crackvis::service_manager {

// Sends `state` ("READY=1", "STOPPING=1", "STATUS=..." lines). Returns true
// when a message was sent; false without $NOTIFY_SOCKET (not started by
// systemd) or when the socket refuses it: a service runs the same either way.
bool notify(std::string_view state);

}  // namespace crackvis::service_manager
