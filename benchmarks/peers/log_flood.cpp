// log_flood: a roscpp publisher of rosgraph_msgs/Log on one topic at a fixed rate, for
// benchmarks/bench_log.py (a rosout aggregate at full speed, with no rosout in the way).
//
// usage: log_flood TOPIC RATE COUNT [--name NAME]
//   waits for one subscriber, then publishes COUNT messages "flood N" at WARN from
//   "/flood", RATE per second against a steady clock (a late loop catches up in a burst),
//   then stays up 2 s so the queue drains.
// stdout: "ready" once advertised, "started", then {"published": COUNT, "seconds": S}.
#include <rosgraph_msgs/Log.h>

#include <algorithm>
#include <thread>

#include "peer.h"

int main(int argc, char** argv) {
  peer::init(argc, argv, "log_flood");
  peer::Args args(argc, argv, "log_flood TOPIC RATE COUNT [--name NAME]", {}, {});
  const std::string topic = args.positional(0);
  const double rate = args.positional_number(1);
  const auto count = uint64_t(args.positional_number(2));
  if (rate <= 0) args.fail("RATE must be positive");
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<rosgraph_msgs::Log>(topic, 100000);
  peer::say("ready");
  while (ros::ok() && pub.getNumSubscribers() == 0) ros::WallDuration(0.01).sleep();
  peer::say("started");
  const auto start = peer::Clock::now();
  rosgraph_msgs::Log msg;
  msg.level = rosgraph_msgs::Log::WARN;
  msg.name = "/flood";
  msg.file = "log_flood.cpp";
  msg.function = "main";
  msg.line = 42;
  msg.topics = {topic};
  uint64_t sent = 0;
  while (ros::ok() && sent < count) {
    const double due = peer::seconds(start, peer::Clock::now()) * rate;
    for (; sent < count && double(sent) <= due; ++sent) {
      msg.header.seq = uint32_t(sent);
      msg.header.stamp = ros::Time::now();
      msg.msg = "flood " + std::to_string(sent);
      pub.publish(msg);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  const double took = peer::seconds(start, peer::Clock::now());
  peer::say("{\"published\": " + std::to_string(sent) + ", \"seconds\": " + std::to_string(took) + "}");
  ros::WallDuration(2.0).sleep();
  return 0;
}
