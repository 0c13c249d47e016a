// multi_pub: a roscpp publisher of many topics at one rate each, for benchmarks/bench_load.py.
//
// usage: multi_pub PREFIX N SIZE RATE DURATION [--wait-subscribers K] [--wait-timeout S]
//                  [--queue Q] [--linger S] [--name NAME] [--anonymous]
//   advertises PREFIX0 .. PREFIX<N-1> as std_msgs/String, data = SIZE bytes of 'x'
//   RATE      messages per second on every topic (> 0)
//   DURATION  seconds: exactly round(RATE * DURATION) messages go out on every topic
//   --wait-subscribers K  start the clock only once every topic has K subscribers connected
//   --wait-timeout S      give up (exit 3) if they are not all connected after S s (default 120)
//   --queue Q             each publisher's queue (default 10000: 10 s at 1 kHz)
//   --linger S            stay up S seconds after the run so queued messages reach subscribers
//                         (default 2)
// stdout: "ready" once advertised, "subscribed" after --wait-subscribers, "started" when the
// clock starts, then one JSON line:
//   {"published": total over all topics, "per_topic": messages on each topic, "topics": N,
//    "seconds": first publish to last, "rate": total / seconds, "behind_max": the most rounds
//    the loop was ever late by, "bytes": size of one serialized message}
//
// Round k (one message on every topic, topics in order) is due k / RATE seconds after the
// start, against a steady clock. The loop publishes every round that is due, then sleeps until
// the next one, but at least 100 us and at most 1 ms (as pub_rate does): the average rate is
// exact, and a late loop catches up in a burst instead of losing rounds.
#include <std_msgs/String.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "peer.h"

int main(int argc, char** argv) {
  peer::init(argc, argv, "multi_pub");
  peer::Args args(argc, argv,
                  "multi_pub PREFIX N SIZE RATE DURATION [--wait-subscribers K] "
                  "[--wait-timeout S] [--queue Q] [--linger S] [--name NAME] [--anonymous]",
                  {}, {"--wait-subscribers", "--wait-timeout", "--queue", "--linger"});
  const std::string prefix = args.positional(0);
  const auto topics = size_t(args.positional_number(1));
  const auto size = size_t(args.positional_number(2));
  const double rate = args.positional_number(3);
  const double duration = args.positional_number(4);
  if (topics == 0) args.fail("N must be at least 1");
  if (rate <= 0) args.fail("RATE must be > 0");
  const auto rounds = uint64_t(std::llround(rate * duration));
  const auto queue = uint32_t(args.number("--queue", 10000));
  const auto wanted = uint32_t(args.number("--wait-subscribers", 0));
  const double wait_timeout = args.number("--wait-timeout", 120.0);
  const double linger = args.number("--linger", 2.0);

  ros::NodeHandle nh;
  std::vector<ros::Publisher> pubs;
  pubs.reserve(topics);
  for (size_t i = 0; i < topics; ++i) {
    pubs.push_back(nh.advertise<std_msgs::String>(prefix + std::to_string(i), queue));
  }
  std_msgs::String msg;
  msg.data.assign(size, 'x');
  peer::say("ready");

  if (wanted > 0) {
    const auto since = peer::Clock::now();
    auto all_there = [&]() {
      return std::all_of(pubs.begin(), pubs.end(),
                         [&](const ros::Publisher& p) { return p.getNumSubscribers() >= wanted; });
    };
    while (ros::ok() && !all_there()) {
      if (peer::seconds(since, peer::Clock::now()) > wait_timeout) {
        size_t short_of = 0;
        for (const auto& p : pubs) short_of += p.getNumSubscribers() < wanted ? 1 : 0;
        std::cerr << short_of << " of " << topics << " topics still lack " << wanted
                  << " subscriber(s) after " << wait_timeout << " s" << std::endl;
        return 3;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    peer::say("subscribed");
  }
  if (!ros::ok()) return 1;

  uint64_t sent_rounds = 0;
  uint64_t behind_max = 0;
  peer::Clock::time_point first, last;
  const auto start = peer::Clock::now();
  peer::say("started");
  while (ros::ok() && sent_rounds < rounds) {
    const double elapsed = peer::seconds(start, peer::Clock::now());
    const auto due = std::min<uint64_t>(rounds, uint64_t(elapsed * rate) + 1);
    behind_max = std::max(behind_max, due - sent_rounds);
    for (; sent_rounds < due; ++sent_rounds) {
      for (auto& p : pubs) p.publish(msg);
      last = peer::Clock::now();
      if (sent_rounds == 0) first = last;
    }
    if (sent_rounds >= rounds) break;
    const double wait = double(sent_rounds) / rate - peer::seconds(start, peer::Clock::now());
    if (wait > 0) {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::clamp(wait, 100e-6, 1e-3)));
    }
  }
  const double span = sent_rounds > 1 ? peer::seconds(first, last) : 0.0;
  const uint64_t published = sent_rounds * topics;
  peer::Json out;
  out.add("published", published)
      .add("per_topic", sent_rounds)
      .add("topics", uint64_t(topics))
      .add("seconds", span)
      .add("rate", span > 0 ? double(published) / span : 0.0)
      .add("behind_max", behind_max)
      .add("bytes", uint64_t(ros::serialization::serializationLength(msg)));
  peer::say(out.str());

  // Queued messages are written by roscpp's network thread; shutting down drops them.
  const auto until = peer::Clock::now() + std::chrono::duration<double>(linger);
  while (ros::ok() && peer::Clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return 0;
}
