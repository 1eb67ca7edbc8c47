"""The `vmnav` command line and thin tools around package code.

Importing it limits BLAS to one thread (:mod:`tools.threads`), before the command
imports numpy, scipy or OpenCV.
"""

from tools.threads import one_blas_thread

one_blas_thread()
