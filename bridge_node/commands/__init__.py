"""The ``icebridge`` command line: ``cli`` parses, one module per subcommand does the work.

Every subcommand module has ``add_arguments(parser)`` and ``run(args) -> int``; none imports
another (shared pieces live in ``node``, ``render``, ``reports`` and ``library``).
"""
