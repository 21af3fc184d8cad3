mod ray_query;
