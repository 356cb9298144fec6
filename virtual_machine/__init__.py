"""virtual_machine"""
