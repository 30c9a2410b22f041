// rtlab bench — a time limit for work that may never return: a driver stuck in its compiler, a
// kernel that does not end. The work runs on a thread of its own and the caller waits for it at
// most so long. Work that overruns is left running, detached, with what it captured, so it must
// hold shared ownership of what it uses; the caller records the timeout, never touches those
// objects again, and ends the process with std::_Exit (workAbandoned() says when), because
// destructors and the driver's exit handlers could wait on the stuck thread.
#pragma once

#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <optional>
#include <thread>
#include <utility>

namespace rt::bench {

// True once some work was left running past its limit.
inline std::atomic<bool>& workAbandoned() {
    static std::atomic<bool> abandoned{false};
    return abandoned;
}

// work()'s result when it ends within `seconds` (its exception is rethrown here), or
// std::nullopt when it does not. seconds <= 0: no limit, and work() runs on the calling thread.
template <typename F>
auto withinSeconds(double seconds, F work) -> std::optional<decltype(work())> {
    using R = decltype(work());
    if (seconds <= 0) return work();
    auto task = std::make_shared<std::packaged_task<R()>>(std::move(work));
    std::future<R> result = task->get_future();
    std::thread([task] { (*task)(); }).detach();
    if (result.wait_for(std::chrono::duration<double>(seconds)) == std::future_status::timeout) {
        workAbandoned() = true;
        return std::nullopt;
    }
    return result.get();
}

}  // namespace rt::bench
