//! Compiles the vendored TetGen 1.5 and the `extern "C"` shim into one static library.

fn main() {
    for path in ["shim/shim.cpp", "tetgen/tetgen.cxx", "tetgen/tetgen.h", "tetgen/predicates.cxx"] {
        println!("cargo:rerun-if-changed={path}");
    }
    cc::Build::new()
        .cpp(true)
        .include("tetgen")
        // The vendored tetgen.h also defines TETLIBRARY (empty, hence `Some("")`: an identical
        // redefinition, no warning); defining it here keeps the library build independent of that.
        .define("TETLIBRARY", Some(""))
        // Fixed rather than following the cargo profile: TetGen at -O0/-O1 is several times
        // slower, and tests mesh real geometries.
        .opt_level(2)
        // Shewchuk's predicates need every product rounded on its own; a fused multiply-add
        // (the default contraction on targets with FMA) breaks their error bounds.
        .flag_if_supported("-ffp-contract=off")
        // Third-party code: its warnings are not ours to fix.
        .warnings(false)
        .flag_if_supported("-Wno-unused-parameter")
        .flag_if_supported("-Wno-unused-but-set-variable")
        .flag_if_supported("-Wno-unused-result")
        .flag_if_supported("-Wno-maybe-uninitialized")
        .flag_if_supported("-Wno-int-to-pointer-cast")
        .flag_if_supported("-Wno-write-strings")
        .file("tetgen/predicates.cxx")
        .file("tetgen/tetgen.cxx")
        .file("shim/shim.cpp")
        .compile("amber_tetgen");
}
