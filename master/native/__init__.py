"""The native FMUs (C, no Python inside): models' constants, data file, sources and build."""
