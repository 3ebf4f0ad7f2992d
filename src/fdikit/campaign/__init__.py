"""Campaigns: Monte Carlo over plants × faults × designs × evaluators, resumable, on a process pool or Dask."""
