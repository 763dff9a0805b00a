#include <algorithm>
#include <exception>
#include <utility>

#include "simreel/render/frame_sink.hpp"

namespace simreel::render {

FrameWriter::FrameWriter(std::vector<std::unique_ptr<FrameSink>> sinks, std::size_t depth)
    : depth_(depth) {
  for (auto& sink : sinks) {
    auto lane = std::make_unique<Lane>();
    lane->sink = std::move(sink);
    lanes_.push_back(std::move(lane));
  }
  if (depth_ == 0) return;
  // Threads start once every lane exists: run() never sees lanes_ change.
  for (auto& lane : lanes_) {
    const int threads = std::max(1, lane->sink->concurrency());
    lane->capacity = depth_ + static_cast<std::size_t>(threads - 1);
    lane->running = threads;
    for (int t = 0; t < threads; ++t) lane->threads.emplace_back([this, l = lane.get()] { run(*l); });
  }
}

FrameWriter::~FrameWriter() {
  {
    const std::lock_guard lock(mutex_);
    aborting_ = true;
    closing_ = true;
  }
  work_.notify_all();
  for (auto& lane : lanes_) {
    if (!lane->threads.empty()) {
      for (auto& thread : lane->threads) {
        if (thread.joinable()) thread.join();
      }
    } else if (!lane->finished) {
      lane->sink->abort();
    }
  }
}

void FrameWriter::run(Lane& lane) {
  for (;;) {
    Item item;
    {
      std::unique_lock lock(mutex_);
      work_.wait(lock, [&] { return aborting_ || lane.failed || !lane.queue.empty() || closing_; });
      if (aborting_ || lane.failed) break;
      if (lane.queue.empty()) break;  // closing and drained
      item = std::move(lane.queue.front());
      lane.queue.pop_front();
      ++lane.in_flight;
    }
    std::string error;
    try {
      lane.sink->write(*item.frame, item.index);
    } catch (const IoError& e) {
      error = e.what();
    }
    {
      const std::lock_guard lock(mutex_);
      --lane.in_flight;
      if (!error.empty() && !lane.failed) {
        lane.failed = true;
        lane.queue.clear();
        failures_.push_back({lane.sink->describe(), error});
      }
    }
    space_.notify_all();
    if (!error.empty()) {
      work_.notify_all();  // the lane's other threads stop too
      break;
    }
  }
  // The last of the lane's threads to return closes the sink, after every write has ended.
  bool abort_sink = false;
  {
    const std::lock_guard lock(mutex_);
    if (--lane.running > 0) return;
    abort_sink = aborting_ || lane.failed;
  }
  if (abort_sink) {
    lane.sink->abort();
  } else {
    // Finishing here closes several videos at once; ffmpeg flushing its encoder is slow.
    std::string error;
    try {
      lane.sink->finish();
    } catch (const IoError& e) {
      error = e.what();
    }
    const std::lock_guard lock(mutex_);
    if (error.empty()) {
      lane.finished = true;
    } else {
      lane.failed = true;
      failures_.push_back({lane.sink->describe(), error});
    }
  }
  space_.notify_all();
}

void FrameWriter::write(Image frame, int index) {
  write(std::make_shared<const Image>(std::move(frame)), index);
}

void FrameWriter::write(std::shared_ptr<const Image> shared, int index) {
  if (depth_ == 0) {
    for (auto& lane : lanes_) {
      if (lane->failed) continue;
      try {
        lane->sink->write(*shared, index);
      } catch (const IoError& e) {
        lane->failed = true;
        lane->sink->abort();
        failures_.push_back({lane->sink->describe(), e.what()});
      }
    }
    return;
  }
  {
    std::unique_lock lock(mutex_);
    space_.wait(lock, [&] {
      return std::all_of(lanes_.begin(), lanes_.end(), [&](const auto& l) {
        return l->failed || l->queue.size() + l->in_flight < l->capacity;
      });
    });
    for (auto& lane : lanes_) {
      if (!lane->failed) lane->queue.push_back({shared, index});
    }
  }
  work_.notify_all();
}

std::vector<std::string> FrameWriter::finish() {
  {
    const std::lock_guard lock(mutex_);
    closing_ = true;
  }
  work_.notify_all();
  std::vector<std::string> done;
  for (auto& lane : lanes_) {
    if (!lane->threads.empty()) {
      for (auto& thread : lane->threads) {
        if (thread.joinable()) thread.join();
      }
    } else if (depth_ == 0 && !lane->failed && !lane->finished) {
      try {
        lane->sink->finish();
        lane->finished = true;
      } catch (const IoError& e) {
        lane->failed = true;
        failures_.push_back({lane->sink->describe(), e.what()});
      }
    }
    if (lane->finished) done.push_back(lane->sink->describe());
  }
  return done;
}

std::vector<FrameWriter::Failure> FrameWriter::take_failures() {
  const std::lock_guard lock(mutex_);
  return std::exchange(failures_, {});
}

}  // namespace simreel::render
