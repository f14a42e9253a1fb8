"""The built-in sports' mappings (Section 7), one module per sport, and the pieces they share."""
