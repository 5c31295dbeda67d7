"""Accuracy as a budget: the user says how wrong a reflection may be (or how long a frame
may take), and each reflector of each frame is drawn by the cheapest candidate predicted
to meet it (see docs/budget.md)."""
