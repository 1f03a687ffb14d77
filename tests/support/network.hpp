// Loopback addresses for tests of what a client says when nothing answers.
#pragma once

namespace crackvis::testing {

// A 127.0.0.1 port that nothing listens on: one the OS just gave out and
// took back (a connection to it is refused).
int closedPort();

}  // namespace crackvis::testing
