// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A fixed set of worker threads for the short fork-join loops of one tracked frame.
// Waiting threads sleep on a condition variable. (OpenMP's workers busy-wait between
// parallel regions; when another process holds one of the cores, every region then waits
// for a scheduler time slice and two threads run several times slower than one.)
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace unseen {

class ThreadPool {
 public:
  // `threads` in total, the calling thread included (so threads - 1 workers); 0 means all
  // hardware threads. Throws unseen::Error for a negative count.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }

  // Runs fn(i) for every i in [0, n) on the calling thread and the workers, each index
  // once, and returns when all have finished. The first exception thrown by fn is
  // rethrown here (the other indices still run). One loop at a time: fn must not call
  // ParallelFor of the same pool.
  void ParallelFor(int n, const std::function<void(int)>& fn);

 private:
  void WorkerLoop();
  // Takes indices of the current loop until none is left.
  void RunIndices();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable work_ready_, work_done_;
  bool stop_ = false;
  long generation_ = 0;  // incremented for every loop
  int busy_workers_ = 0; // workers still inside the current loop
  const std::function<void(int)>* fn_ = nullptr;
  int n_ = 0;
  int next_ = 0;  // next index to hand out (under mutex_)
  std::exception_ptr error_;
};

}  // namespace unseen
