// PNG encoding on a background thread, so that writing one frame overlaps rendering the next (PNG and zlib
// were a third of the main thread's time at 1024², `perf`).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace pmfrag::render {

class PngQueue {
 public:
  /// At most `depth` images wait to be written (memory stays bounded); push blocks beyond that.
  explicit PngQueue(std::size_t depth = 2);
  /// Writes what is queued, then stops the thread. Call finish() first to learn of errors.
  ~PngQueue();
  PngQueue(const PngQueue&) = delete;
  PngQueue& operator=(const PngQueue&) = delete;
  /// Waits until every queued image is on disk; throws std::runtime_error with the first write error.
  void finish();

  struct Job;  // pixels and where they go (png.cpp)
  /// Queues a job; throws the first earlier write error instead of queuing more.
  void push(std::unique_ptr<Job> job);

 private:
  void work();
  std::size_t depth_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::unique_ptr<Job>> jobs_;
  bool closing_ = false, busy_ = false;
  std::string error_;
  std::thread worker_;  // last: started after the members it uses
};

}  // namespace pmfrag::render
