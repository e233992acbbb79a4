"""Actions of the example library."""
