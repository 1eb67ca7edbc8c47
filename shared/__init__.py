"""Pure code used by more than one of robot/, ground/ and sim/.

Nothing here imports robot/, ground/, sim/ or tools/, and nothing here does I/O
beyond the explicit file loaders (config, calibration) that validate what they read.
"""
