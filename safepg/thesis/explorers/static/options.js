// The run options' names, defaults and allowed values, for the page learner (vector_run.js).
// Generated from safepg.options by `python -m safepg.thesis.explorers.option_names`: do not edit;
// tests/test_option_names.py fails when it is not what that command writes.
"use strict";
safepgLearner.OPTIONS = {
 "methods": [
  "Adaptive",
  "Vanilla"
 ],
 "run": {
  "budget": {
   "default": 1000000,
   "field": "budget",
   "integer": true
  },
  "seed": {
   "default": 0,
   "field": "seed",
   "integer": true
  },
  "sigma": {
   "default": 1.0,
   "field": "sigma",
   "number": true
  },
  "stopOnDivergence": {
   "choices": [
    true,
    false
   ],
   "default": true,
   "field": "stop_on_divergence"
  },
  "theta0": {
   "default": 0.0,
   "field": "theta0",
   "list": true,
   "number": true
  }
 },
 "types": {
  "Adaptive": {
   "batches": {
    "default": "Batches",
    "field": "batches",
    "nested": true,
    "types": [
     "Batches"
    ]
   },
   "departures": {
    "default": "Departures",
    "field": "departures",
    "nested": true,
    "types": [
     "Departures"
    ]
   },
   "error": {
    "default": "ErrorModel",
    "field": "error",
    "nested": true,
    "types": [
     "ErrorModel"
    ]
   },
   "gradient": {
    "default": "Gradient",
    "field": "gradient",
    "nested": true,
    "types": [
     "Gradient"
    ]
   }
  },
  "Batches": {
   "first": {
    "default": null,
    "field": "first",
    "integer": true,
    "nullable": true
   },
   "nMax": {
    "default": 500000,
    "field": "n_max",
    "integer": true
   },
   "nMin": {
    "default": 100,
    "field": "n_min",
    "integer": true
   }
  },
  "Departures": {
   "batchConstants": {
    "choices": [
     true,
     false
    ],
    "default": false,
    "field": "batch_constants"
   },
   "maxima": {
    "choices": [
     true,
     false
    ],
    "default": false,
    "field": "maxima"
   },
   "unguardedStep": {
    "choices": [
     true,
     false
    ],
    "default": false,
    "field": "unguarded_step"
   }
  },
  "ErrorModel": {
   "bound": {
    "choices": [
     "chebyshev",
     "hoeffding",
     "bernstein"
    ],
    "default": "chebyshev",
    "field": "bound"
   },
   "delta": {
    "default": 0.95,
    "field": "delta",
    "number": true
   },
   "range": {
    "choices": [
     "lemma",
     "empirical"
    ],
    "default": "lemma",
    "field": "range",
    "number": true
   }
  },
  "FixedStep": {
   "alpha": {
    "field": "alpha",
    "number": true
   },
   "kind": {
    "choices": [
     "scalar",
     "coordinate"
    ],
    "default": "scalar",
    "field": "kind"
   }
  },
  "Gradient": {
   "baseline": {
    "choices": [
     true,
     false
    ],
    "default": true,
    "field": "baseline"
   },
   "estimator": {
    "choices": [
     "reinforce",
     "gpomdp"
    ],
    "default": "gpomdp",
    "field": "estimator"
   },
   "scoreAction": {
    "choices": [
     "clipped",
     "raw"
    ],
    "default": "clipped",
    "field": "score_action"
   }
  },
  "SafeStep": {
   "error": {
    "default": "ErrorModel",
    "field": "error",
    "nested": true,
    "types": [
     "ErrorModel"
    ]
   },
   "kind": {
    "choices": [
     "scalar",
     "coordinate"
    ],
    "default": "coordinate",
    "field": "kind"
   }
  },
  "Target": {
   "update": {
    "choices": [
     true,
     false
    ],
    "default": false,
    "field": "update"
   },
   "value": {
    "field": "value",
    "number": true
   }
  },
  "Vanilla": {
   "batchSize": {
    "field": "batch_size",
    "integer": true
   },
   "gradient": {
    "default": "Gradient",
    "field": "gradient",
    "nested": true,
    "types": [
     "Gradient"
    ]
   },
   "step": {
    "default": "FixedStep",
    "field": "step",
    "nested": false,
    "types": [
     "FixedStep",
     "SafeStep"
    ]
   },
   "target": {
    "default": null,
    "field": "target",
    "nested": false,
    "nullable": true,
    "types": [
     "Target"
    ]
   }
  }
 }
};
