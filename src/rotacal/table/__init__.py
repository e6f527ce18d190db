"""rotacal.table"""
