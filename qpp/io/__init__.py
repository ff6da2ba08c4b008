"""The qpp config, its schema, the stored design and the stage runners."""
