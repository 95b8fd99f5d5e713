/**
 * @file bmi.h
 * @brief dpsm as a BMI 2.0 component in C (`libdpsm_bmi`): the function
 *        table of CSDMS's Basic Model Interface and its registration.
 *
 * The struct ::Bmi has the member order, the signatures and the constants of
 * the `bmi.h` of CSDMS's C binding (github.com/csdms/bmi-c, BMI 2.0), which
 * NOAA's NextGen also uses. When a framework's own `bmi.h` (include guard
 * `BMI_H`) was included first, this header takes its ::Bmi and declares
 * only the two registration functions; included first, it defines `BMI_H`
 * so that the framework's copy adds nothing.
 *
 * A host fills a ::Bmi with register_bmi_dpsm() (or `register_bmi`, the name
 * NextGen looks up with `dlsym`), then calls `initialize` with the path of a
 * YAML configuration, `update` or `update_until`, the getters and setters,
 * and `finalize`. docs/guide_bmi.md lists the variables, the grids and the
 * keys of the configuration. Every function returns ::BMI_SUCCESS or
 * ::BMI_FAILURE; BMI has no message channel, so a failure writes one line
 * naming the function and the problem to stderr.
 */
#ifndef DPSM_BMI_H
#define DPSM_BMI_H

/** @cond INTERNAL */
#if defined(_WIN32)
#  ifdef DPSM_BUILDING_BMI
#    define DPSM_BMI_API __declspec(dllexport)
#  else
#    define DPSM_BMI_API __declspec(dllimport)
#  endif
#elif defined(__GNUC__)
#  define DPSM_BMI_API __attribute__((visibility("default")))
#else
#  define DPSM_BMI_API
#endif
/** @endcond */

#ifdef __cplusplus
extern "C" {
#endif

#ifndef BMI_H
/** The include guard of CSDMS's `bmi.h`: defined here, a framework's copy included later adds nothing. */
#define BMI_H

/** A BMI function succeeded. */
#define BMI_SUCCESS (0)
/** A BMI function failed (the component says why on stderr). */
#define BMI_FAILURE (1)

/** Room a host gives get_var_units() (characters, with the terminating zero). */
#define BMI_MAX_UNITS_NAME (2048)
/** Room a host gives get_var_type() and get_grid_type(). */
#define BMI_MAX_TYPE_NAME (2048)
/** Room a host gives get_component_name(). */
#define BMI_MAX_COMPONENT_NAME (2048)
/** Room a host gives each name of get_input_var_names() and get_output_var_names(). */
#define BMI_MAX_VAR_NAME (2048)

/**
 * @brief The BMI 2.0 function table, as CSDMS's C binding declares it.
 *
 * `data` is the component's state: NULL until `initialize` succeeds, NULL
 * again after `finalize`. Every member takes the table itself as `self`.
 */
typedef struct Bmi {
    /** The component's state, owned by the component. */
    void *data;

    /** Reads the YAML configuration at `config_file` and builds the scene. */
    int (*initialize)(struct Bmi *self, const char *config_file);
    /** Advances by the time step (the last one shortened to land on the end time). */
    int (*update)(struct Bmi *self);
    /** Advances to time `then` in time steps and a final partial one. */
    int (*update_until)(struct Bmi *self, double then);
    /** Releases the scene; `data` becomes NULL. */
    int (*finalize)(struct Bmi *self);

    /** Writes "dpsm". */
    int (*get_component_name)(struct Bmi *self, char *name);
    /** Number of input variables. */
    int (*get_input_item_count)(struct Bmi *self, int *count);
    /** Number of output variables. */
    int (*get_output_item_count)(struct Bmi *self, int *count);
    /** Copies the input names into `names[0 ..]`, each of ::BMI_MAX_VAR_NAME characters. */
    int (*get_input_var_names)(struct Bmi *self, char **names);
    /** Copies the output names into `names[0 ..]`, each of ::BMI_MAX_VAR_NAME characters. */
    int (*get_output_var_names)(struct Bmi *self, char **names);

    /** The grid a variable lives on. */
    int (*get_var_grid)(struct Bmi *self, const char *name, int *grid);
    /** Writes "double". */
    int (*get_var_type)(struct Bmi *self, const char *name, char *type);
    /** Writes the variable's units ("m", "m s-1", "degree", "m3 s-1", "m3": UDUNITS-2 names). */
    int (*get_var_units)(struct Bmi *self, const char *name, char *units);
    /** Bytes per value: 8. */
    int (*get_var_itemsize)(struct Bmi *self, const char *name, int *size);
    /** Bytes of the whole variable. */
    int (*get_var_nbytes)(struct Bmi *self, const char *name, int *nbytes);
    /** Writes "node", "edge" or "face". */
    int (*get_var_location)(struct Bmi *self, const char *name, char *location);

    /** The model's time, in seconds. */
    int (*get_current_time)(struct Bmi *self, double *time);
    /** 0. */
    int (*get_start_time)(struct Bmi *self, double *time);
    /** The configuration's `time.end`. */
    int (*get_end_time)(struct Bmi *self, double *time);
    /** Writes "s". */
    int (*get_time_units)(struct Bmi *self, char *units);
    /** The configuration's `time.step`. */
    int (*get_time_step)(struct Bmi *self, double *time_step);

    /** Copies a variable's values into `dest`. */
    int (*get_value)(struct Bmi *self, const char *name, void *dest);
    /** Points `*dest_ptr` at the component's copy of a variable: valid until
     *  `finalize`, refreshed by every update and set, for reading only
     *  (writing through it changes nothing in the model; use set_value). */
    int (*get_value_ptr)(struct Bmi *self, const char *name, void **dest_ptr);
    /** Copies the values at `count` flat indices `inds` into `dest`. */
    int (*get_value_at_indices)(struct Bmi *self, const char *name, void *dest, int *inds, int count);

    /** Sets an input variable from `src`. */
    int (*set_value)(struct Bmi *self, const char *name, void *src);
    /** Sets an input variable at `count` flat indices `inds` from `src`. */
    int (*set_value_at_indices)(struct Bmi *self, const char *name, int *inds, int count, void *src);

    /** Number of dimensions of a grid (0 for the scalars). */
    int (*get_grid_rank)(struct Bmi *self, int grid, int *rank);
    /** Number of nodes of a grid. */
    int (*get_grid_size)(struct Bmi *self, int grid, int *size);
    /** Writes "uniform_rectilinear", "unstructured" or "scalar". */
    int (*get_grid_type)(struct Bmi *self, int grid, char *type);

    /** A uniform rectilinear grid's shape, slowest dimension first ([ny, nx]). */
    int (*get_grid_shape)(struct Bmi *self, int grid, int *shape);
    /** Its spacing ([dy, dx]), in m. */
    int (*get_grid_spacing)(struct Bmi *self, int grid, double *spacing);
    /** Its first node ([y, x]), in m. */
    int (*get_grid_origin)(struct Bmi *self, int grid, double *origin);

    /** x of the nodes: along the x axis on a rectilinear grid, of every node on a mesh. */
    int (*get_grid_x)(struct Bmi *self, int grid, double *x);
    /** y of the nodes, as get_grid_x(). */
    int (*get_grid_y)(struct Bmi *self, int grid, double *y);
    /** z of the nodes: the grids of dpsm are flat, so this fails. */
    int (*get_grid_z)(struct Bmi *self, int grid, double *z);

    /** Number of nodes. */
    int (*get_grid_node_count)(struct Bmi *self, int grid, int *count);
    /** Number of edges of a mesh. */
    int (*get_grid_edge_count)(struct Bmi *self, int grid, int *count);
    /** Number of faces (cells) of a mesh. */
    int (*get_grid_face_count)(struct Bmi *self, int grid, int *count);
    /** The two nodes of every edge. */
    int (*get_grid_edge_nodes)(struct Bmi *self, int grid, int *edge_nodes);
    /** The edges of every face, face after face. */
    int (*get_grid_face_edges)(struct Bmi *self, int grid, int *face_edges);
    /** The nodes of every face, face after face. */
    int (*get_grid_face_nodes)(struct Bmi *self, int grid, int *face_nodes);
    /** The number of nodes of every face. */
    int (*get_grid_nodes_per_face)(struct Bmi *self, int grid, int *nodes_per_face);
} Bmi;

#endif /* BMI_H */

/**
 * @brief Fills the function table of `model` with dpsm's BMI functions.
 *
 * Sets `model->data` to NULL; `initialize` then creates the component's
 * state. One table is one independent model; a process may hold several.
 *
 * @param model  the table to fill; NULL is allowed and returns NULL.
 * @return `model`.
 */
DPSM_BMI_API Bmi *register_bmi_dpsm(Bmi *model);

/**
 * @brief As register_bmi_dpsm(): the registration function NextGen looks up
 *        by its default name.
 * @param model  the table to fill; NULL is allowed and returns NULL.
 * @return `model`.
 */
DPSM_BMI_API Bmi *register_bmi(Bmi *model);

#ifdef __cplusplus
}
#endif

#endif
