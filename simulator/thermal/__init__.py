"""Heat transfer: the steady thermal model (T3 conduction plus environment chains),
transient heat and power schedules."""
