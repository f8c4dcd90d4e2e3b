#include "progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace nimbus::cli {

bool stderr_is_terminal() { return isatty(STDERR_FILENO) == 1; }

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled), start_(std::chrono::steady_clock::now()), last_(start_) {}

void ProgressBar::update(int64_t done, int64_t total, int64_t samples) {
  if (!enabled_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  if (done < total && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double frac = total > 0 ? double(done) / double(total) : 1.0;
  const int width = 30, filled = int(frac * width);
  const double rate = elapsed > 0 ? samples / elapsed : 0.0;
  const double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
  fmt::print(stderr, "\r{} [{}{}] {:5.1f}%  {:.3g} samples/s  ETA {:.0f}s   ", label_,
             std::string(filled, '#'), std::string(width - filled, '.'), 100.0 * frac, rate, eta);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::stage(const std::string& text) {
  if (!enabled_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  fmt::print(stderr, "\r{} {} ({:.1f}s)          ", label_, text, elapsed);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (drawn_) fmt::print(stderr, "\n");
  drawn_ = false;
}

}  // namespace nimbus::cli
