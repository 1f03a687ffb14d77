# Writes INPUT's text into OUTPUT as a C++ raw string constant.
file(READ ${INPUT} text)
file(WRITE ${OUTPUT} "// Generated from pipeline-schemas/pipeline.xsd; do not edit.\n#pragma once\n\n"
     "namespace crackvis::pipeline {\ninline constexpr const char* kPipelineSchemaText = R\"xsd(${text})xsd\";\n}\n")
