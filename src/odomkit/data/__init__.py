"""Built-in sample data (OptiOdom, MIT licence: see LICENSE-OptiOdom.txt)."""
