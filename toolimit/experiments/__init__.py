"""The paper's experiments on top of the pipeline: the results figure's cells, their measurement and report."""
