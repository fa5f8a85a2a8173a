"""neuropils"""
