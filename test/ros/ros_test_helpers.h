#pragma once
// Helpers of the rostests: a subscription that keeps what arrived and waits for
// a condition with a timeout (never a bare sleep), and a /rosout watcher.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include <ros/master.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>

namespace vitamin_e_test {

template <class Msg>
class Watcher {
 public:
  Watcher(ros::NodeHandle& nh, const std::string& topic, uint32_t queue = 100) {
    sub_ = nh.subscribe<Msg>(topic, queue, [this](const typename Msg::ConstPtr& msg) {
      std::lock_guard<std::mutex> lock(mutex_);
      messages_.push_back(msg);
      cv_.notify_all();
    });
  }
  // Waits (callbacks run on an AsyncSpinner) until pred(messages) holds.
  bool waitFor(const std::function<bool(const std::vector<typename Msg::ConstPtr>&)>& pred, double timeout_s) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!pred(messages_)) {
      if (!ros::ok() || cv_.wait_until(lock, deadline) == std::cv_status::timeout) return pred(messages_);
    }
    return true;
  }
  bool waitForCount(std::size_t n, double timeout_s) {
    return waitFor([n](const auto& m) { return m.size() >= n; }, timeout_s);
  }
  bool waitForPublisher(double timeout_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (sub_.getNumPublishers() == 0) {
      if (!ros::ok() || std::chrono::steady_clock::now() > deadline) return false;
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait_for(lock, std::chrono::milliseconds(20));  // connection has no event to wait on: poll
    }
    return true;
  }
  // Waits until the subscription is connected to every publisher the master lists for its topic
  // (at least one). /rosout has one per node, this test's own among them: waitForPublisher() may
  // return before the node whose one-off message a test waits for is connected.
  bool waitForAllPublishers(double timeout_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      XmlRpc::XmlRpcValue request, response, payload;
      request[0] = ros::this_node::getName();
      int listed = 0;
      if (ros::master::execute("getSystemState", request, response, payload, false) && payload.size() > 0) {
        XmlRpc::XmlRpcValue& publishers = payload[0];  // [[topic, [node, ...]], ...]
        for (int i = 0; i < publishers.size(); ++i) {
          if (static_cast<std::string>(publishers[i][0]) == sub_.getTopic()) listed = publishers[i][1].size();
        }
      }
      if (listed > 0 && sub_.getNumPublishers() >= static_cast<uint32_t>(listed)) return true;
      if (!ros::ok() || std::chrono::steady_clock::now() > deadline) return false;
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait_for(lock, std::chrono::milliseconds(20));  // connection has no event to wait on: poll
    }
  }
  std::vector<typename Msg::ConstPtr> messages() {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.clear();
  }

 private:
  ros::Subscriber sub_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<typename Msg::ConstPtr> messages_;
};

// Waits for a message of at least `level` on /rosout whose text contains every needle.
inline bool waitForLog(Watcher<rosgraph_msgs::Log>& rosout, std::uint8_t level, const std::vector<std::string>& needles,
                       double timeout_s) {
  return rosout.waitFor(
      [&](const std::vector<rosgraph_msgs::Log::ConstPtr>& logs) {
        for (const auto& log : logs) {
          if (log->level < level) continue;
          bool all = true;
          for (const auto& n : needles) all = all && log->msg.find(n) != std::string::npos;
          if (all) return true;
        }
        return false;
      },
      timeout_s);
}

// Waits for an ERROR (or FATAL) on /rosout whose text contains `needle`.
inline bool waitForLogError(Watcher<rosgraph_msgs::Log>& rosout, const std::string& needle, double timeout_s) {
  return waitForLog(rosout, rosgraph_msgs::Log::ERROR, {needle}, timeout_s);
}

}  // namespace vitamin_e_test

namespace vitamin_e_test {

// A private parameter of the test node (string), or fallback.
inline std::string privateParam(const std::string& name, const std::string& fallback = "") {
  std::string value;
  ros::NodeHandle("~").param(name, value, fallback);
  return value;
}

}  // namespace vitamin_e_test
