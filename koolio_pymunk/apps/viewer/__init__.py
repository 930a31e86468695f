"""Drawing and the interactive window (pygame-ce). Nothing here is imported by the core."""
