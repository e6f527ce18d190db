"""rotacal.encoder"""
