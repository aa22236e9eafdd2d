"""Insertion trials: one trial (runner), batches (local or Ray), summaries and charts."""
