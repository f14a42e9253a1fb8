"""Section 7: the physical state -> per-bone pose channels. numpy only, one module per sport."""
