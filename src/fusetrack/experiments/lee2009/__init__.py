"""Lee 2009 (seed 000): projected-plane acoustic tracking, triggered cameras, detection fusion, RFID + cameras.

Scenarios, constants and experiments of the paper; uses the library and is never imported by it.
"""
