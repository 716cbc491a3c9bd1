"""What every layer of the node shares, below links, stream, render and the exercise: the
user's errors, file and path checks, network rules, TOML error texts, child processes."""
