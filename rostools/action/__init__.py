"""actionlib over topics: a client and a server of ROS 1 actions on the live node.

An action ``/fib`` is five topics: the client publishes ``/fib/goal`` and ``/fib/cancel``;
the server publishes ``/fib/status``, ``/fib/feedback`` and ``/fib/result``. ``status.py`` and
``graph.py`` are plain data (the completer uses them without asyncio); ``client.py`` and
``server.py`` run on ``rostools.node``.
"""
