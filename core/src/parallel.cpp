#include "bsdflab/parallel.h"
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace bsdflab {

unsigned worker_count() {
    if (const char *env = std::getenv("BSDFLAB_THREADS")) {
        long v = std::strtol(env, nullptr, 10);
        if (v >= 1) return static_cast<unsigned>(v);
    }
    return std::max(1u, std::thread::hardware_concurrency());
}

void parallel_for(std::size_t n, std::size_t grain,
                  const std::function<void(std::size_t, std::size_t)> &body) {
    if (n == 0) return;
    std::size_t workers =
        std::min<std::size_t>(worker_count(), (n + grain - 1) / std::max<std::size_t>(grain, 1));
    if (workers <= 1) {
        body(0, n);
        return;
    }
    std::size_t chunk = (n + workers - 1) / workers;
    std::vector<std::thread> threads;
    std::exception_ptr error;
    std::mutex error_mutex;
    for (std::size_t w = 0; w < workers; ++w) {
        std::size_t begin = w * chunk, end = std::min(n, begin + chunk);
        if (begin >= end) break;
        threads.emplace_back([&, begin, end] {
            try {
                body(begin, end);
            } catch (...) {
                std::lock_guard<std::mutex> lock(error_mutex);
                if (!error) error = std::current_exception();
            }
        });
    }
    for (auto &t : threads) t.join();
    if (error) std::rethrow_exception(error);
}

void parallel_for_each(std::size_t n, const std::function<void(std::size_t)> &body) {
    std::atomic<std::size_t> next{0};
    std::size_t workers = std::min<std::size_t>(worker_count(), n);
    parallel_for(workers, 1, [&](std::size_t, std::size_t) {
        for (std::size_t i = next++; i < n; i = next++) body(i);
    });
}

} // namespace bsdflab
