"""rotacal.sim"""
