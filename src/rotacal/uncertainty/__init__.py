"""rotacal.uncertainty"""
