"""Tables and figures (the only place that imports matplotlib) and report assembly."""
