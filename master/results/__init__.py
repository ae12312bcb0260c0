"""A run's results: the streamed time series, statistics, plots and result files."""
