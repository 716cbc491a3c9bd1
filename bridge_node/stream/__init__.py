"""The state stream: what the physics process publishes after every step, for render
processes on this PC or others (ZeroMQ PUB/SUB with a snapshot service, as the Clone
pattern of the ZeroMQ guide)."""
