// log_levels: a roscpp node that logs at every level, a round every 0.1 s: "LEVEL N".
//
// usage: log_levels [--name NAME=log_levels_cpp]
// stdout: "ready" once it logs; it logs until SIGINT.
#include "peer.h"

int main(int argc, char** argv) {
  peer::init(argc, argv, "log_levels_cpp");
  peer::Args args(argc, argv, "log_levels [--name NAME=log_levels_cpp] [--anonymous]", {}, {});
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(1);  // the logger services are served while the loop sleeps
  spinner.start();
  peer::say("ready");
  ros::WallRate rate(10);
  for (uint64_t n = 0; ros::ok(); ++n) {
    ROS_DEBUG("debug %lu", static_cast<unsigned long>(n));
    ROS_INFO("info %lu", static_cast<unsigned long>(n));
    ROS_WARN("warn %lu", static_cast<unsigned long>(n));
    ROS_ERROR("error %lu", static_cast<unsigned long>(n));
    ROS_FATAL("fatal %lu", static_cast<unsigned long>(n));
    rate.sleep();
  }
  return 0;
}
