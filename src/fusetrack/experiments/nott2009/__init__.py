"""Nott 2009 (seed 004): one camera + radio tag fused in an EKF.

Scenarios, constants and experiments of the paper; uses the library and is never imported by it.
"""
