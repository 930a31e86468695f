"""The top floor: what a person runs.

The ``koolio-pm`` command line (:mod:`.cli`), the simulator window (:mod:`.viewer`), the
arena editor (:mod:`.editor`), learning curves (:mod:`.plotting`), sweeps
(:mod:`.sweep`), the policy export (:mod:`.export`) and the transfer experiment
(:mod:`.transfer`).

May import from every floor below; nothing below imports from here.
"""
