"""rotacal.signal"""
