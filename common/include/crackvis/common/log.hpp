// The services' log lines: a UTC timestamp, the program, an event name and
// key=value fields, strings quoted with control characters escaped (so a
// hostile file name cannot forge a line). The access log uses the same form:
//
//   2026-11-22T03:05:00.123Z crackvis-render event=serving address="127.0.0.1:50052" tls="mutual"
#pragma once

#include <cstdio>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>

namespace crackvis::log {

// "2026-11-22T03:05:00.123Z"
std::string utcNow();
// "\"text\"" with '"', '\\' and control characters escaped.
std::string quoted(std::string_view text);

using Field = std::pair<std::string_view, std::string>;
// Writes one line and flushes it (service logs go to pipes and journals).
void event(std::FILE* out, std::string_view program, std::string_view name,
           std::initializer_list<Field> fields);

}  // namespace crackvis::log
