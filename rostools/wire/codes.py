"""The status codes of ROS's XML-RPC answers, ``[code, status message, value]``.

Their meanings are the ROS Master/Slave API's: ``ERROR``, the caller's mistake (a bad
argument, an unknown parameter, node or service), so nothing was done; ``FAILURE``, the
server tried and failed (rosmaster's "Internal failure"); ``SUCCESS``, done. This module
imports nothing, so the blocking clients use it at no start-up cost.
"""

ERROR = -1
FAILURE = 0
SUCCESS = 1
