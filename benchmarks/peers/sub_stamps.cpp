// sub_stamps: a roscpp subscriber that notes when each std_msgs/String arrives, for timing
// `bag play` (benchmarks/bench_bag_live.py).
//
// usage: sub_stamps TOPIC --count N [--idle S] [--timeout S]
//   --count    stop after N messages
//   --idle     stop once no message came for S seconds, after the first (default 2)
//   --timeout  stop S seconds after start-up, whatever arrived (default 60)
// Every message's data is its index in the bag as decimal text.
// stdout: "ready" once subscribed, then one line "INDEX NANOSECONDS" per message (steady clock),
// then "done RECEIVED".
//
// The arrival times are kept in memory and printed only at the end, so writing to the pipe never
// delays a callback. TCP_NODELAY is requested so that the player, not Nagle's algorithm, decides
// when each small message leaves the publisher.
#include <std_msgs/String.h>

#include <cstdlib>
#include <utility>
#include <vector>

#include "peer.h"

namespace {

std::vector<std::pair<long, int64_t>> arrivals;

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             peer::Clock::now().time_since_epoch())
      .count();
}

void on_message(const std_msgs::String::ConstPtr& msg) {
  const int64_t t = now_ns();
  arrivals.emplace_back(std::strtol(msg->data.c_str(), nullptr, 10), t);
}

}  // namespace

int main(int argc, char** argv) {
  peer::init(argc, argv, "sub_stamps");
  peer::Args args(argc, argv, "sub_stamps TOPIC --count N [--idle S] [--timeout S]", {},
                  {"--count", "--idle", "--timeout"});
  const std::string topic = args.positional(0);
  const auto count = size_t(args.number("--count", 0));
  const double idle = args.number("--idle", 2.0);
  const double timeout = args.number("--timeout", 60.0);
  if (count == 0) args.fail("--count N is required");
  arrivals.reserve(count);

  ros::NodeHandle nh;
  // A deep callback queue: a late callback must show up as a late time, not as a lost message.
  ros::Subscriber sub =
      nh.subscribe<std_msgs::String>(topic, 100000, on_message, ros::TransportHints().tcpNoDelay());
  peer::say("ready");

  const auto start = peer::Clock::now();
  auto* callbacks = ros::getGlobalCallbackQueue();
  while (ros::ok() && arrivals.size() < count) {
    // Blocks on a condition variable until a message is queued, so the wake-up is immediate.
    callbacks->callAvailable(ros::WallDuration(0.1));
    const auto now = peer::Clock::now();
    if (peer::seconds(start, now) >= timeout) break;
    if (!arrivals.empty()) {
      const auto last = peer::Clock::time_point(std::chrono::nanoseconds(arrivals.back().second));
      if (peer::seconds(last, now) >= idle) break;
    }
  }
  std::string out;
  out.reserve(arrivals.size() * 24);
  for (const auto& [index, t] : arrivals) {
    out += std::to_string(index) + ' ' + std::to_string(t) + '\n';
  }
  std::cout << out;
  peer::say("done " + std::to_string(arrivals.size()));
  return 0;
}
