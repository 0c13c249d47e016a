"""The bundled ROS master and parameter server."""
