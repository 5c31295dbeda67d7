"""The sphere-map lab's judge (placeholder until written)."""
