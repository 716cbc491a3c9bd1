"""Hardware links of the bridge console: one ``Link`` interface, one module per protocol."""
