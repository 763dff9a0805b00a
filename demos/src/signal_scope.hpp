// A command's own signal handlers, for as long as it needs them (render's gentle first Ctrl-C,
// sweep passing signals on), over main()'s hard stop (render::remove_temporaries_on_signals).
#pragma once

#include <signal.h>

#include <initializer_list>

namespace simreel::app {

/// Installs `handler` for each of `signals` (at most 4) while it lives and restores the previous
/// actions when it ends. A signal the parent set to be ignored (nohup, a background job) stays
/// ignored. restart: SA_RESTART, so interrupted system calls resume; without it a blocking call
/// (waitpid) returns EINTR at the signal.
class SignalScope {
 public:
  SignalScope(void (*handler)(int), std::initializer_list<int> signals, bool restart) {
    struct sigaction action {};
    action.sa_handler = handler;
    sigemptyset(&action.sa_mask);
    action.sa_flags = restart ? SA_RESTART : 0;
    for (const int s : signals) {
      if (count_ == 4) break;
      signals_[count_] = s;
      sigaction(s, nullptr, &old_[count_]);
      if (old_[count_].sa_handler != SIG_IGN) sigaction(s, &action, nullptr);
      ++count_;
    }
  }
  ~SignalScope() {
    for (int i = 0; i < count_; ++i) sigaction(signals_[i], &old_[i], nullptr);
  }
  SignalScope(const SignalScope&) = delete;
  SignalScope& operator=(const SignalScope&) = delete;

 private:
  int signals_[4] = {};
  struct sigaction old_[4] {};
  int count_ = 0;
};

}  // namespace simreel::app
