"""The instructor station: a web page served by its own process (``icebridge instructor``)
that draws the exercise live from the state stream and commands it through the node's
control endpoint."""
