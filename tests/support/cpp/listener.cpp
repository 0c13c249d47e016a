// listener: the plain roscpp listener of the ROS tutorials, on std_msgs/String.
//
// usage: listener [TOPIC=/chatter] [--count N] [--name NAME=listener] [--anonymous]
// stdout: "ready" once subscribed, then "got <data>" for every message; exits after N messages
// with --count, else on SIGINT.
#include <std_msgs/String.h>

#include "peer.h"

namespace {

uint64_t received = 0;

void on_message(const std_msgs::String::ConstPtr& msg) {
  peer::say("got " + msg->data);
  ++received;
}

}  // namespace

int main(int argc, char** argv) {
  peer::init(argc, argv, "listener");
  peer::Args args(argc, argv, "listener [TOPIC=/chatter] [--count N] [--name NAME] [--anonymous]",
                  {}, {"--count"});
  const std::string topic = args.positional(0, "/chatter");
  const auto count = uint64_t(args.number("--count", 0));

  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe(topic, 1000, on_message);
  peer::say("ready");
  while (ros::ok() && (count == 0 || received < count)) {
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.05));
  }
  return 0;
}
