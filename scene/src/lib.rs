//! Mesh loading, the meshlet LOD DAG builder and the meshlet asset format.
