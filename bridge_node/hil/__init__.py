"""Hardware-in-the-loop testing: a software bridge console, scenario files, fault injection,
the bench that runs the node and the console in separate processes, and the reports."""
