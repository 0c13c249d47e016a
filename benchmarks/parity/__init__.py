"""Parity with the ROS 1 tools: each command and its rostools twin on one graph, compared.

``python -m benchmarks.parity`` (see ``__main__``). ``compare`` normalises and judges a
pair of outputs, ``documented`` lists the known differences and where the docs say so,
``graph`` builds the graph on either master, ``runner`` runs one side of a case, and
``cases``/``cases_offline`` are the cases.
"""
