"""rotacal.io"""
