"""Wind fields: running mean (synoptic, downburst) and turbulence synthesis."""
