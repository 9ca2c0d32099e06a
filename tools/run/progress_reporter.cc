#include "tools/run/progress_reporter.h"

#include <algorithm>
#include <cstdio>
#include <string>

namespace rslam::run {

ProgressReporter::ProgressReporter(std::ostream& out, Style style, int64_t total_frames)
    : out_(out), style_(style), total_(total_frames), start_(Clock::now()), last_print_(start_) {}

void ProgressReporter::Update(uint64_t frames, uint64_t templates, uint64_t experiences) {
  if (style_ == Style::kQuiet) return;
  const auto now = Clock::now();
  const auto period = style_ == Style::kBar ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
  if (now - last_print_ < period) return;
  last_print_ = now;
  Print(frames, templates, experiences);
}

void ProgressReporter::Finish(uint64_t frames, uint64_t templates, uint64_t experiences) {
  if (style_ == Style::kQuiet) return;
  Print(frames, templates, experiences);
  if (style_ == Style::kBar) out_ << "\n";
  out_.flush();
}

void ProgressReporter::Print(uint64_t frames, uint64_t templates, uint64_t experiences) {
  const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
  const double fps = seconds > 0 ? static_cast<double>(frames) / seconds : 0.0;
  // std::string::append, not "literal" + std::string: GCC 12 warns -Wrestrict on the latter (a false positive)
  const std::string of_total = total_ >= 0 ? std::string("/").append(std::to_string(total_)) : "";
  char counts[160];
  std::snprintf(counts, sizeof counts, "%llu%s frames  %.1f fps  %llu templates  %llu experiences",
                static_cast<unsigned long long>(frames), of_total.c_str(), fps,
                static_cast<unsigned long long>(templates), static_cast<unsigned long long>(experiences));
  if (style_ == Style::kLines) {
    out_ << "rslam run: " << counts << "\n";
    out_.flush();
    return;
  }
  constexpr int kWidth = 30;
  std::string bar;
  if (total_ > 0) {
    const double done = std::min(1.0, static_cast<double>(frames) / static_cast<double>(total_));
    const int filled = static_cast<int>(done * kWidth);
    bar.append("[").append(filled, '#').append(kWidth - filled, '.').append("] ");
    bar.append(std::to_string(static_cast<int>(done * 100))).append("%  ");
  }
  out_ << "\r" << bar << counts << "\x1b[K";
  out_.flush();
  printed_ = true;
}

}  // namespace rslam::run
