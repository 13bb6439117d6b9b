"""The commands on a live ROS 2 graph, over the ROS binding (:mod:`dynevent.ros`): ``dynevent serve``
(:mod:`~dynevent.tools.live.serve`), ``send`` (:mod:`~dynevent.tools.live.send`), ``record``
(:mod:`~dynevent.tools.live.record`) and ``probe`` (:mod:`~dynevent.tools.live.probe`).  Each module
needs ROS 2 to import; the command line checks a command's own input before it imports one.
"""
