mod brdf_eval;
