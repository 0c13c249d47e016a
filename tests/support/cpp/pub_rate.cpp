// pub_rate: a roscpp publisher that holds an exact average rate, for benchmarks.
//
// usage: pub_rate TOPIC TYPE SIZE RATE DURATION [--latch] [--wait-subscribers N] [--count N]
//                 [--queue Q] [--linger S] [--name NAME] [--anonymous]
//   TYPE      std_msgs/String (data = SIZE bytes of 'x') or sensor_msgs/Image (mono8, 1 row of
//             SIZE pixels, header.stamp = the time of each publish)
//   RATE      messages per second; 0 = as fast as possible
//   DURATION  seconds; at RATE > 0 exactly round(RATE * DURATION) messages are published
//   --count N          stop after N messages even if DURATION has not passed
//   --wait-subscribers start the clock only once N subscribers are connected
//   --queue Q          publisher queue (default: as many messages as fit in 256 MiB, 10..100000)
//   --linger S         stay up S seconds after the run so queued messages reach subscribers
//                      (default 1; negative = until SIGINT, e.g. for a latched last message)
// stdout: "ready" once advertised, "subscribers N" after --wait-subscribers, "started" when the
// clock starts, then one JSON line:
//   {"published": N, "seconds": S, "rate": R, "target_rate": ..., "bytes": size of one
//    serialized message, "t_first": epoch s, "t_last": epoch s}
// where S is the time from the first publish to the last and R = (N - 1) / S, the mean
// frequency as `rostopic hz` computes it.
//
// Sleeping once per message cannot hold 200 kHz (a sleep alone costs ~60 us), so the loop
// publishes every message that is due against a steady clock (message k is due at k / RATE),
// then sleeps until the next one is due, but at least 100 us and at most 1 ms.
#include <sensor_msgs/Image.h>
#include <std_msgs/String.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "peer.h"

namespace {

struct Plan {
  double rate = 0;
  double duration = 0;
  uint64_t total = 0;  // messages to publish; UINT64_MAX when only the duration limits
};

// Stamp messages that carry a header, so a subscriber could measure latency.
void stamp(std_msgs::String&) {}
void stamp(sensor_msgs::Image& msg) { msg.header.stamp = ros::Time::now(); }

template <class M>
void run(ros::Publisher& pub, M& msg, const Plan& plan) {
  uint64_t sent = 0;
  peer::Clock::time_point first, last;
  double t_first = 0;
  const auto start = peer::Clock::now();
  peer::say("started");
  auto publish_one = [&]() {
    stamp(msg);
    pub.publish(msg);
    last = peer::Clock::now();
    if (sent == 0) {
      first = last;
      t_first = peer::epoch_now();
    }
    ++sent;
  };
  while (ros::ok() && sent < plan.total) {
    const double elapsed = peer::seconds(start, peer::Clock::now());
    if (plan.rate <= 0) {
      if (elapsed >= plan.duration) break;
      // As fast as possible: a burst between clock readings keeps the clock off the hot path.
      for (int i = 0; i < 64 && sent < plan.total; ++i) publish_one();
      continue;
    }
    const auto due = std::min<uint64_t>(plan.total, uint64_t(elapsed * plan.rate) + 1);
    while (sent < due) publish_one();
    if (sent >= plan.total) break;
    const double wait = double(sent) / plan.rate - peer::seconds(start, peer::Clock::now());
    if (wait > 0) {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::clamp(wait, 100e-6, 1e-3)));
    }
  }
  const double span = sent > 1 ? peer::seconds(first, last) : 0.0;
  peer::Json out;
  out.add("published", sent)
      .add("seconds", span)
      .add("rate", span > 0 ? double(sent - 1) / span : 0.0)
      .add("target_rate", plan.rate)
      .add("bytes", uint64_t(ros::serialization::serializationLength(msg)))
      .add_epoch("t_first", t_first)
      .add_epoch("t_last", t_first + span);
  peer::say(out.str());
}

}  // namespace

int main(int argc, char** argv) {
  peer::init(argc, argv, "pub_rate");
  peer::Args args(argc, argv,
                  "pub_rate TOPIC TYPE SIZE RATE DURATION [--latch] [--wait-subscribers N] "
                  "[--count N] [--queue Q] [--linger S] [--name NAME] [--anonymous]",
                  {"--latch"}, {"--wait-subscribers", "--count", "--queue", "--linger"});
  const std::string topic = args.positional(0);
  const std::string type = args.positional(1);
  const auto size = uint64_t(args.positional_number(2));
  Plan plan;
  plan.rate = args.positional_number(3);
  plan.duration = args.positional_number(4);
  plan.total = plan.rate > 0 ? uint64_t(std::llround(plan.rate * plan.duration)) : UINT64_MAX;
  if (args.number("--count", 0) > 0) {
    plan.total = std::min(plan.total, uint64_t(args.number("--count", 0)));
  }
  // Deep enough that the publisher never drops while the subscriber keeps up on average, yet
  // bounded in memory for big messages.
  const double fit = (256.0 * 1024 * 1024) / double(size + 64);
  const auto queue = uint32_t(args.number("--queue", std::clamp(fit, 10.0, 100000.0)));
  const bool latch = args.flag("--latch");
  // Before the NodeHandle: its constructor starts the node and would wait for a master.
  if (type != "std_msgs/String" && type != "sensor_msgs/Image") {
    args.fail("TYPE must be std_msgs/String or sensor_msgs/Image, not " + type);
  }

  ros::NodeHandle nh;
  std_msgs::String text;
  sensor_msgs::Image image;
  ros::Publisher pub;
  if (type == "std_msgs/String") {
    text.data.assign(size, 'x');
    pub = nh.advertise<std_msgs::String>(topic, queue, latch);
  } else if (type == "sensor_msgs/Image") {
    image.height = 1;
    image.width = uint32_t(size);
    image.encoding = "mono8";
    image.step = uint32_t(size);
    image.data.assign(size, 0x5a);
    pub = nh.advertise<sensor_msgs::Image>(topic, queue, latch);
  }
  peer::say("ready");

  const auto wanted = uint32_t(args.number("--wait-subscribers", 0));
  if (wanted > 0) {
    while (ros::ok() && pub.getNumSubscribers() < wanted) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    peer::say("subscribers " + std::to_string(pub.getNumSubscribers()));
  }
  if (!ros::ok()) return 1;

  if (type == "std_msgs/String") {
    run(pub, text, plan);
  } else {
    run(pub, image, plan);
  }

  const double linger = args.number("--linger", 1.0);
  if (linger < 0) {
    ros::waitForShutdown();
  } else {
    // Queued messages are written by roscpp's network thread; shutting down drops them.
    const auto until = peer::Clock::now() + std::chrono::duration<double>(linger);
    while (ros::ok() && peer::Clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  return 0;
}
