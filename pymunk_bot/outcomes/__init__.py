"""What a run yields: expectations and their verdict, per-tick metrics, the navigation
metrics of crowds (``navigation/``), run logs, and result files written atomically."""
