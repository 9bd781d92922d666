"""Live recognition as data and as an evaluation: the sliding-window recogniser
(:mod:`.recognizer`), decision rules (:mod:`.rules`), streams built from
datasets (:mod:`.timeline`) and their replay (:mod:`.replay`)."""
