"""Sans-IO ROS 1 protocol code over bytes: TCPROS headers, frames, XML-RPC conventions."""
