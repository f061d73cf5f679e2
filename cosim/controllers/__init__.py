"""Controller timing models: SimPy processes that drive and read signals, never FMUs."""
