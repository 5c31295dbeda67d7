"""Render passes, one pass type per module. Each draws into a target it is given."""
