"""What the readings themselves show, before any model: still intervals and pose means
(:mod:`.static`), steps, the data's own noise and the converter's rounding (:mod:`.noise`),
clipping and rails, held (repeated) readings, why a recording holds no rest, and the rule
that names poses far off a fit."""
