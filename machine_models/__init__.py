"""machine_models"""
