"""What the vehicle senses: the depth camera (:mod:`.sensor`) and the estimator's noise and the wind
(:mod:`.noise`)."""
