"""The instructor's control of a running exercise: commands (their wire form, checked), the
queue the tick takes them from, the control endpoint on the node and its client."""
