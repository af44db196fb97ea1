"""Zhai 2007 (seed 001): better particle filters — EKF-bank, multiple-model, Galerkin and grid proposals, MCMC moves.

Scenarios, constants and experiments of the paper; uses the library and is never imported by it.
"""
