#pragma once
// SIGINT and SIGTERM end a service cleanly: main blocks them before any thread starts and
// waits for one; every node then saves its state in its destructor.

#include <chrono>

namespace rslam {

// Blocks SIGINT/SIGTERM in the calling thread and every thread it creates afterwards.
void BlockShutdownSignals();
// Waits for SIGINT or SIGTERM (or RequestShutdown); returns the signal number (0 if requested).
// With a period, calls on_tick every period while waiting.
int WaitForShutdown(std::chrono::milliseconds period = std::chrono::milliseconds(0), void (*on_tick)(void*) = nullptr,
                    void* arg = nullptr);
// Makes WaitForShutdown return (e.g. when a node finishes its input).
void RequestShutdown();

}  // namespace rslam
