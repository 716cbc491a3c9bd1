"""IceBridge bridge node: hardware links, real-time loop, render channels, CLI."""
