// Injected preemption, for tests of races between threads. A race whose window is a few
// instructions wide (one thread between two steps while another completes a longer sequence) is
// opened by the scheduler's own preemption once in millions of passes; a test that waits for that
// cannot fail reliably. A thread holding a ScopedPreemption is instead paused for `pause` about
// every `period` of wall-clock time, at whatever instruction it is executing: a POSIX timer of its
// own (timer_create with SIGEV_THREAD_ID) sends it a real-time signal whose handler sleeps
// (nanosleep is async-signal-safe; SA_RESTART resumes interrupted system calls). Every window is
// widened to `pause` that often, while the other threads run on.
#pragma once

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <mutex>

namespace ltm::test {

class ScopedPreemption {
public:
    ScopedPreemption(std::chrono::microseconds period, std::chrono::microseconds pause) {
        pause_ns().store(static_cast<long>(std::chrono::nanoseconds(pause).count()));
        static std::once_flag installed;
        std::call_once(installed, [] {
            struct sigaction sa {};
            sa.sa_handler = [](int) {
                const long ns = pause_ns().load();
                timespec t{ns / 1000000000L, ns % 1000000000L};
                nanosleep(&t, nullptr);
            };
            sa.sa_flags = SA_RESTART;
            sigemptyset(&sa.sa_mask);
            sigaction(signal(), &sa, nullptr);
        });
        sigevent ev{};
        ev.sigev_notify = SIGEV_THREAD_ID;
        ev.sigev_signo = signal();
        ev._sigev_un._tid = static_cast<pid_t>(syscall(SYS_gettid));
        armed_ = timer_create(CLOCK_MONOTONIC, &ev, &timer_) == 0;
        EXPECT_TRUE(armed_) << "timer_create failed: no preemption is injected";
        if (!armed_) return;
        const long ns = static_cast<long>(std::chrono::nanoseconds(period).count());
        itimerspec spec{};
        spec.it_value = {ns / 1000000000L, ns % 1000000000L};
        spec.it_interval = spec.it_value;
        timer_settime(timer_, 0, &spec, nullptr);
    }
    ~ScopedPreemption() {
        if (armed_) timer_delete(timer_);
    }
    ScopedPreemption(const ScopedPreemption&) = delete;
    ScopedPreemption& operator=(const ScopedPreemption&) = delete;

private:
    static int signal() { return SIGRTMIN + 3; }
    static std::atomic<long>& pause_ns() {
        static std::atomic<long> ns{0};
        return ns;
    }
    timer_t timer_{};
    bool armed_ = false;
};

}  // namespace ltm::test
