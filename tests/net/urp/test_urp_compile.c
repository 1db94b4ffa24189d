/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urp/test_urp_compile.c — .urp programs to URScript: URCL's own program files, one
 * synthetic program per supported node (the generated URScript compared whole), the External
 * Control slots, and every way a file can be bad (gzip, XML, unknown nodes). */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_support.h"
#include "urp_test_util.h"
#include "urt/net/urp.h"

//---- helpers ----

/* Compile xml (gzip'd here) and render without External Control text; NULL on failure with
 * why filled. */
static char *compile_xml(const char *xml, const urt_urp_options_t *opt, char *why, size_t why_sz,
                         int *external) {
  size_t len = 0;
  unsigned char *gz = urp_test_gzip(xml, &len);
  urt_urp_program_t *p = NULL;
  int rc = urt_urp_compile(gz, len, opt, &p, why, why_sz);
  free(gz);
  if (rc != 0) {
    return NULL;
  }
  char *text = NULL;
  size_t tl = 0;
  assert_int_equal(urt_urp_render(p, NULL, NULL, &text, &tl), 0);
  assert_int_equal(strlen(text), tl);
  if (external) *external = urt_urp_external_nodes(p);
  urt_urp_free(p);
  return text;
}

/* body inside a run-once MainProgram compiles to exactly `expect`. */
static void expect_body(const char *body, const char *expect) {
  char *xml = urp_test_program("prog", "true", NULL, body);
  char why[256] = "";
  char *text = compile_xml(xml, NULL, why, sizeof why, NULL);
  free(xml);
  if (!text) fail_msg("compile failed: %s", why);
  if (strcmp(text, expect) != 0) {
    fail_msg("generated:\n%s\nexpected:\n%s", text, expect);
  }
  free(text);
}

/* body fails to compile with a reason containing `needle`. */
static void expect_error(const char *body, const char *needle) {
  char *xml = urp_test_program("prog", "true", NULL, body);
  char why[256] = "";
  char *text = compile_xml(xml, NULL, why, sizeof why, NULL);
  free(xml);
  if (text) fail_msg("compiled, expected an error with '%s':\n%s", needle, text);
  if (!strstr(why, needle)) fail_msg("error '%s' lacks '%s'", why, needle);
}

#define PROG(lines) "def prog():\n" lines "end\n"

//---- URCL's programs (the first real examples) ----

static const char *urcl_programs(const char *series, const char *file) {
  static char path[1024];
  const char *roots[] = {"/../shared", "/../../shared"};
  for (int k = 0; k < 2; k++) {
    snprintf(path, sizeof path,
             "%s%s/clients/Universal_Robots_Client_Library-2.14.0/tests/resources/dockerursim/"
             "programs/%s/%s",
             URT_SOURCE_DIR, roots[k], series, file);
    if (access(path, R_OK) == 0) {
      return path;
    }
  }
  return NULL;
}

static void test_urcl_wait_program(void **state) {
  (void)state;
  const char *series[] = {"cb3", "e-series"};
  for (int k = 0; k < 2; k++) {
    const char *path = urcl_programs(series[k], "wait_program.urp");
    if (!path) {
      print_message("SKIP: ../shared (URCL 2.14.0's programs) is absent\n");
      skip();
    }
    urt_urp_program_t *p = NULL;
    char why[256];
    if (urt_urp_compile_file(path, NULL, &p, why, sizeof why) != 0) fail_msg("%s: %s", path, why);
    assert_string_equal(urt_urp_name(p), "wait_program");
    assert_int_equal(urt_urp_external_nodes(p), 0);
    char *text;
    size_t len;
    assert_int_equal(urt_urp_render(p, NULL, NULL, &text, &len), 0);
    // runOnlyOnce="false": the program loops forever, as PolyScope runs it
    assert_string_equal(text,
                        "def wait_program():\n"
                        "  while (True):\n"
                        "    sleep(0.01)\n"
                        "  end\n"
                        "end\n");
    free(text);
    urt_urp_free(p);
  }
}

static void test_urcl_external_control(void **state) {
  (void)state;
  const char *series[] = {"cb3", "e-series"};
  for (int k = 0; k < 2; k++) {
    const char *path = urcl_programs(series[k], "external_control.urp");
    if (!path) {
      print_message("SKIP: ../shared (URCL 2.14.0's programs) is absent\n");
      skip();
    }
    urt_urp_program_t *p = NULL;
    char why[256];
    if (urt_urp_compile_file(path, NULL, &p, why, sizeof why) != 0) fail_msg("%s: %s", path, why);
    assert_string_equal(urt_urp_name(p), "external_control");
    assert_int_equal(urt_urp_external_nodes(p), 1);
    char *text;
    size_t len;
    assert_int_equal(urt_urp_render(p, "# HEADER_BEGIN\nsteptime = get_steptime()\n"
                                       "def f():\n  return 1\nend\n# HEADER_END\n",
                                    "# NODE_CONTROL_LOOP_BEGINS\ntextmsg(\"loop\")\n",
                                    &text, &len),
                     0);
    assert_string_equal(text,
                        "def external_control():\n"
                        "  # HEADER_BEGIN\n"
                        "  steptime = get_steptime()\n"
                        "  def f():\n"
                        "    return 1\n"
                        "  end\n"
                        "  # HEADER_END\n"
                        "  # NODE_CONTROL_LOOP_BEGINS\n"
                        "  textmsg(\"loop\")\n"
                        "end\n");
    free(text);
    urt_urp_free(p);
  }
}

//---- one program per node ----

static void test_move_j_l_p(void **state) {
  (void)state;
  expect_body(
      "<Move motionType=\"MoveJ\" speed=\"1.0472\" acceleration=\"1.3962634015954636\" "
      "useActiveTCP=\"false\"><feature class=\"GeomFeatureReference\" referencedName=\"Base\"/>"
      "<children>"
      "<Waypoint type=\"Fixed\" name=\"Waypoint_1\" kinematicsFlags=\"4\"><motionParameters/>"
      "<position><JointAngles angles=\"-1.6, -1.7, -2.2, -0.8, 1.6, -0.03\"/>"
      "<TCPOffset pose=\"0.0, 0.0, 0.12, 0.0, 0.0, 0.0\"/></position>"
      "<BaseToFeature pose=\"0.0, 0.0, 0.0, 0.0, 0.0, 0.0\"/></Waypoint>"
      "<Waypoint type=\"Fixed\" name=\"Waypoint_2\"><motionParameters jointSpeed=\"0.5\" "
      "jointAcceleration=\"0.7\" cartesianSpeed=\"0.1\" blendRadius=\"0.012\"/>"
      "<position><JointAngles angles=\"0, -1.5708, 0, -1.5708, 0, 0\"/></position></Waypoint>"
      "</children></Move>"
      "<Move motionType=\"MoveL\" speed=\"0.25\" acceleration=\"1.2\"><children>"
      "<Waypoint name=\"W3\"><motionParameters cartesianSpeed=\"0.05\"/>"
      "<position joints=\"1, 2, 3, 4, 5, 6\"/></Waypoint>"
      "<Wait type=\"Sleep\"><waitTime>0.5</waitTime></Wait>"
      "<Waypoint name=\"W4\"><position pose=\"0.1, 0.2, 0.3, 0, 3.14, 0\"/></Waypoint>"
      "</children></Move>"
      "<Move motionType=\"MoveP\" speed=\"0.1\" acceleration=\"1.0\" blendRadius=\"0.025\">"
      "<children><Waypoint type=\"Variable\" name=\"Waypoint_5\">"
      "<variable name=\"target_p\" prefersPersistentValue=\"false\"/></Waypoint>"
      "</children></Move>",
      PROG("  movej([-1.6, -1.7, -2.2, -0.8, 1.6, -0.03], a=1.3962634015954636, v=1.0472)\n"
           "  movej([0.0, -1.5708, 0.0, -1.5708, 0.0, 0.0], a=0.7, v=0.5, r=0.012)\n"
           "  movel([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], a=1.2, v=0.05)\n"
           "  sleep(0.5)\n"
           "  movel(p[0.1, 0.2, 0.3, 0.0, 3.14, 0.0], a=1.2, v=0.25)\n"
           "  movep(target_p, a=1.0, v=0.1, r=0.025)\n"));
}

static void test_wait_and_set(void **state) {
  (void)state;
  expect_body(
      "<Wait type=\"Sleep\"><waitTime>2</waitTime></Wait>"
      "<Wait type=\"DigitalInput\"><pin referencedName=\"digital_in[2]\"/>"
      "<digitalValue>1</digitalValue></Wait>"
      "<Wait type=\"DigitalInput\"><pin referencedName=\"tool_in[1]\"/>"
      "<digitalValue>0</digitalValue></Wait>"
      "<Wait type=\"Condition\"><expression><ExpressionToken token=\"counter\"/>"
      "<ExpressionChar character=\"&gt;\"/><ExpressionChar character=\"3\"/></expression></Wait>"
      "<Set type=\"DigitalOutput\"><pin referencedName=\"digital_out[0]\"/>"
      "<digitalValue>1</digitalValue></Set>"
      "<Set type=\"DigitalOutput\"><pin referencedName=\"config_out[3]\"/>"
      "<digitalValue>false</digitalValue></Set>"
      "<Set type=\"DigitalOutput\" outputBit=\"2\" outputValue=\"true\"/>"
      "<Set type=\"AnalogOutput\"><pin referencedName=\"analog_out[1]\"/>"
      "<analogValue>0.25</analogValue></Set>",
      PROG("  sleep(2.0)\n"
           "  while (not(get_standard_digital_in(2) == True)):\n"
           "    sync()\n"
           "  end\n"
           "  while (not(get_tool_digital_in(1) == False)):\n"
           "    sync()\n"
           "  end\n"
           "  while (not(counter>3)):\n"
           "    sync()\n"
           "  end\n"
           "  set_standard_digital_out(0, True)\n"
           "  set_configurable_digital_out(3, False)\n"
           "  set_standard_digital_out(2, True)\n"
           "  set_standard_analog_out(1, 0.25)\n"));
}

static void test_script_line_and_file(void **state) {
  (void)state;
  // a file on disk, for a Script node without a cached copy
  char dir[] = "/tmp/urt_urp_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256];
  snprintf(path, sizeof path, "%s/helpers.script", dir);
  FILE *f = fopen(path, "w");
  fputs("def helper():\n  textmsg(\"from disk\")\nend\n", f);
  fclose(f);

  char *xml = urp_test_program(
      "prog", "true", NULL,
      "<Script type=\"Line\"><expression><ExpressionToken token=\"retract()\"/></expression>"
      "</Script>"
      "<Script type=\"File\"><cachedContents>def grip(w):\n  textmsg(&quot;grip &quot;, w)\r\n"
      "end\n</cachedContents><file resolves-to=\"file\">/programs/grip.script</file></Script>"
      "<Script type=\"File\"><file resolves-to=\"file\">/programs/helpers.script</file></Script>");
  urt_urp_options_t opt = {.script_root = dir};
  char why[256] = "";
  char *text = compile_xml(xml, &opt, why, sizeof why, NULL);
  if (!text) fail_msg("%s", why);
  assert_string_equal(text, PROG("  retract()\n"
                                 "  def grip(w):\n"
                                 "    textmsg(\"grip \", w)\n"
                                 "  end\n"
                                 "  def helper():\n"
                                 "    textmsg(\"from disk\")\n"
                                 "  end\n"));
  free(text);

  // without a programs folder, or outside it, the file is not read
  assert_null(compile_xml(xml, NULL, why, sizeof why, NULL));
  assert_non_null(strstr(why, "no cached contents"));
  free(xml);
  xml = urp_test_program("prog", "true", NULL,
                         "<Script type=\"File\"><file>../../etc/passwd</file></Script>");
  assert_null(compile_xml(xml, &opt, why, sizeof why, NULL));
  assert_non_null(strstr(why, "not found"));
  free(xml);
  unlink(path);
  rmdir(dir);
}

static void test_assignment_and_expressions(void **state) {
  (void)state;
  // the second Assignment refers back to the first's variable (XStream reference)
  expect_body(
      "<Assignment valueSource=\"Expression\"><variable name=\"counter\" "
      "prefersPersistentValue=\"false\"><initializeExpression/></variable>"
      "<expression><ExpressionChar character=\"0\"/></expression></Assignment>"
      "<Assignment valueSource=\"Expression\"><variable reference=\"../../Assignment/variable\"/>"
      "<expression><ExpressionVariable><ProgramVariable reference=\"../../../../Assignment/"
      "variable\"/></ExpressionVariable><ExpressionChar character=\"+\"/>"
      "<ExpressionChar character=\"1\"/></expression></Assignment>"
      "<Assignment><variable name=\"msg\"/><expression><ExpressionChar character=\"&quot;\"/>"
      "<ExpressionChar character=\"h\"/><ExpressionChar character=\"i\"/>"
      "<ExpressionChar character=\"&quot;\"/></expression></Assignment>",
      PROG("  global counter = 0\n"
           "  global counter = counter+1\n"
           "  global msg = \"hi\"\n"));
}

static void test_loops(void **state) {
  (void)state;
  expect_body(
      "<Loop type=\"Forever\"><children><Halt/></children></Loop>"
      "<Loop loopNum=\"3\"><children><Comment comment=\"three\"/></children></Loop>"
      "<Loop type=\"Counting\"><loopNum>2</loopNum><children>"
      "<Loop loopNum=\"4\"><children><Halt/></children></Loop></children></Loop>"
      "<Loop type=\"While\" checkContinuously=\"false\"><expression>"
      "<ExpressionVariable><ProgramVariable name=\"busy\"/></ExpressionVariable>"
      "</expression><children><Wait type=\"Sleep\"><waitTime>0.1</waitTime></Wait></children>"
      "</Loop>",
      PROG("  while (True):\n"
           "    halt\n"
           "  end\n"
           "  Loop_1 = 0\n"
           "  while (Loop_1 < 3):\n"
           "    # three\n"
           "    Loop_1 = Loop_1 + 1\n"
           "  end\n"
           "  Loop_2 = 0\n"
           "  while (Loop_2 < 2):\n"
           "    Loop_3 = 0\n"
           "    while (Loop_3 < 4):\n"
           "      halt\n"
           "      Loop_3 = Loop_3 + 1\n"
           "    end\n"
           "    Loop_2 = Loop_2 + 1\n"
           "  end\n"
           "  while (busy):\n"
           "    sleep(0.1)\n"
           "  end\n"));
}

static void test_if_elseif_else(void **state) {
  (void)state;
  // ElseIf/Else as siblings of the If (how the tree is written) …
  expect_body(
      "<If type=\"If\" checkContinuously=\"false\"><expression>"
      "<ExpressionToken token=\"get_standard_digital_in(0) == True\"/></expression>"
      "<children><Halt/></children></If>"
      "<If type=\"ElseIf\"><expression><ExpressionToken token=\"x &lt; 2\"/></expression>"
      "<children><Comment comment=\"two\"/></children></If>"
      "<If type=\"Else\"><expression/><children><Placeholder/></children></If>"
      "<Halt/>",
      PROG("  if (get_standard_digital_in(0) == True):\n"
           "    halt\n"
           "  elif (x < 2):\n"
           "    # two\n"
           "  else:\n"
           "  end\n"
           "  halt\n"));
  // … and nested at the end of the If's children (other writers)
  expect_body(
      "<If><expression><ExpressionToken token=\"a\"/></expression><children>"
      "<If><expression><ExpressionToken token=\"b\"/></expression><children><Halt/></children>"
      "</If><Comment comment=\"after inner\"/>"
      "<If type=\"Else\"><children><Comment comment=\"else\"/></children></If>"
      "</children></If>",
      PROG("  if (a):\n"
           "    if (b):\n"
           "      halt\n"
           "    end\n"
           "    # after inner\n"
           "  else:\n"
           "    # else\n"
           "  end\n"));
}

static void test_folder_comment_popup_halt(void **state) {
  (void)state;
  expect_body(
      "<Folder name=\"Setup\"><children><Comment comment=\"inside\nthe folder\"/>"
      "<Popup type=\"Message\" haltProgram=\"false\" message=\"Hello &quot;you&quot;\"/>"
      "</children></Folder>"
      "<Popup type=\"Warning\" haltProgram=\"true\" message=\"careful\"/>"
      "<Popup error=\"true\"><message>bad</message></Popup>"
      "<Halt/>",
      PROG("  # inside the folder\n"
           "  popup(\"Hello 'you'\", \"Message\", False, False, blocking=True)\n"
           "  popup(\"careful\", \"Warning\", True, False, blocking=True)\n"
           "  halt\n"
           "  popup(\"bad\", \"Error\", False, True, blocking=True)\n"
           "  halt\n"));
}

static void test_before_start_and_loop_forever(void **state) {
  (void)state;
  char *xml = urp_test_program("My Prog-2", "false",
                               "<Set type=\"DigitalOutput\"><pin referencedName=\"digital_out[1]\"/>"
                               "<digitalValue>0</digitalValue></Set>",
                               "<Wait type=\"Sleep\"><waitTime>1</waitTime></Wait>");
  char why[256];
  char *text = compile_xml(xml, NULL, why, sizeof why, NULL);
  free(xml);
  if (!text) fail_msg("%s", why);
  assert_string_equal(text,
                      "def My_Prog_2():\n"
                      "  set_standard_digital_out(1, False)\n"
                      "  while (True):\n"
                      "    sleep(1.0)\n"
                      "  end\n"
                      "end\n");
  free(text);
}

static void test_external_control_slots(void **state) {
  (void)state;
  // two nodes: the header once at the top, the body at each node, indented to it
  char *xml = urp_test_program(
      "ec", "true", NULL,
      "<Contributed strategyClass=\"com.fzi.externalcontrol.ExternalControlNode\" "
      "strategyProgramNodeType=\"External Control\"><dataModel/></Contributed>"
      "<Loop loopNum=\"2\"><children>"
      "<Contributed strategyClass=\"com.fzi.externalcontrol.ExternalControlNode\"/>"
      "</children></Loop>");
  size_t len = 0;
  unsigned char *gz = urp_test_gzip(xml, &len);
  free(xml);
  urt_urp_program_t *p;
  char why[256];
  assert_int_equal(urt_urp_compile(gz, len, NULL, &p, why, sizeof why), 0);
  free(gz);
  assert_int_equal(urt_urp_external_nodes(p), 2);
  char *text;
  size_t tl;
  assert_int_equal(urt_urp_render(p, "# HEADER_BEGIN\nglobal g = 1\n# HEADER_END\n",
                                  "textmsg(g)\n  sync()\n", &text, &tl),
                   0);
  assert_string_equal(text,
                      "def ec():\n"
                      "  # HEADER_BEGIN\n"
                      "  global g = 1\n"
                      "  # HEADER_END\n"
                      "  textmsg(g)\n"
                      "    sync()\n"
                      "  Loop_1 = 0\n"
                      "  while (Loop_1 < 2):\n"
                      "    textmsg(g)\n"
                      "      sync()\n"
                      "    Loop_1 = Loop_1 + 1\n"
                      "  end\n"
                      "end\n");
  free(text);
  // the template survives its program: render a copy
  size_t n;
  const char *tmpl = urt_urp_template(p, &n);
  char *copy = malloc(n);
  memcpy(copy, tmpl, n);
  urt_urp_free(p);
  assert_int_equal(urt_urp_render_template(copy, n, NULL, "halt\n", &text, &tl), 0);
  assert_non_null(strstr(text, "def ec():\n  halt\n  Loop_1 = 0\n"));
  free(text);
  free(copy);
}

//---- refusals ----

static void test_unsupported_nodes(void **state) {
  (void)state;
  expect_error("<Timer action=\"Start\"><variable name=\"t\"/></Timer>",
               "unsupported program node 'Timer'");
  expect_error("<CallSubProgram><subprogram name=\"s\"/></CallSubProgram>",
               "unsupported program node 'CallSubProgram'");
  expect_error("<Contributed strategyClass=\"com.onrobot.urcap.unified.OR_RG\" "
               "strategyProgramNodeType=\"RG Grip\"/>",
               "unsupported program node 'Contributed' (RG Grip)");
  expect_error("<Move motionType=\"MoveC\"><children/></Move>",
               "unsupported program node 'Move' (MoveC)");
  expect_error("<Move><children><Waypoint type=\"Relative\" name=\"R\"/></children></Move>",
               "unsupported program node 'Waypoint' (Relative waypoint 'R')");
  expect_error("<Loop type=\"While\" checkContinuously=\"true\"><expression>"
               "<ExpressionToken token=\"a\"/></expression><children/></Loop>",
               "unsupported program node 'Loop' (checking the expression continuously)");
  expect_error("<Wait type=\"AnalogInput\"/>", "unsupported program node 'Wait' (AnalogInput)");
  expect_error("<Set type=\"DigitalOutput\"><pin referencedName=\"digital_out[0]\"/>"
               "<digitalValue>1</digitalValue><payload mass=\"1\"/></Set>",
               "unsupported program node 'Set' (with payload)");
  expect_error("<Assignment valueSource=\"Operator\"><variable name=\"x\"/></Assignment>",
               "unsupported program node 'Assignment' (value from Operator)");
  // a node deep inside containers is found as well
  expect_error("<Folder><children><Loop><children><Gripper/></children></Loop></children>"
               "</Folder>",
               "unsupported program node 'Gripper'");
}

static void test_bad_values(void **state) {
  (void)state;
  expect_error("<Wait type=\"Sleep\"><waitTime>soon</waitTime></Wait>", "waitTime 'soon'");
  expect_error("<Move><children><Waypoint name=\"W\"><position><JointAngles angles=\"1, 2\"/>"
               "</position></Waypoint></children></Move>",
               "not six numbers");
  expect_error("<Set type=\"DigitalOutput\"><pin referencedName=\"digital_out[9]\"/>"
               "<digitalValue>1</digitalValue></Set>",
               "unsupported pin 'digital_out[9]'");
  expect_error("<Assignment><variable reference=\"../../Nothing/variable\"/>"
               "<expression><ExpressionChar character=\"1\"/></expression></Assignment>",
               "does not resolve");
  expect_error("<Assignment><variable name=\"x; halt\"/><expression>"
               "<ExpressionChar character=\"1\"/></expression></Assignment>",
               "not a variable name");
  // an expression cannot smuggle a second statement onto its own line
  expect_error("<Script type=\"Line\"><expression><ExpressionToken token=\"a()&#10;halt\"/>"
               "</expression></Script>",
               "line break");
  expect_error("<If type=\"Else\"><children/></If>", "Else without an If");
  expect_error("<Waypoint name=\"lost\"/>", "Waypoint outside a Move");
}

static void test_bad_files(void **state) {
  (void)state;
  char why[256];
  urt_urp_program_t *p = (urt_urp_program_t *)0x1;

  // not gzip at all (the dashboard test's "<urp/>" file, for instance)
  assert_int_equal(urt_urp_compile("<urp/>\n", 7, NULL, &p, why, sizeof why), -1);
  assert_string_equal(why, "not a gzip file");

  // gzip cut short, and gzip with a corrupted body
  char *xml = urp_test_program("p", "true", NULL, "<Halt/>");
  size_t len = 0;
  unsigned char *gz = urp_test_gzip(xml, &len);
  assert_int_equal(urt_urp_compile(gz, len / 2, NULL, &p, why, sizeof why), -1);
  assert_non_null(strstr(why, "bad gzip data"));
  for (size_t k = 12; k < len - 8; k++) gz[k] ^= 0x5a;
  assert_int_equal(urt_urp_compile(gz, len, NULL, &p, why, sizeof why), -1);
  assert_non_null(strstr(why, "gzip"));
  free(gz);
  free(xml);

  // well-formed gzip, broken XML
  gz = urp_test_gzip("<URProgram><children><MainProgram></children></URProgram>", &len);
  assert_int_equal(urt_urp_compile(gz, len, NULL, &p, why, sizeof why), -1);
  assert_non_null(strstr(why, "bad XML at line 1"));
  free(gz);

  // a DOCTYPE (the door to entity expansion) is refused
  gz = urp_test_gzip("<!DOCTYPE x [<!ENTITY a \"aaaa\">]><URProgram/>", &len);
  assert_int_equal(urt_urp_compile(gz, len, NULL, &p, why, sizeof why), -1);
  assert_non_null(strstr(why, "DOCTYPE"));
  free(gz);

  // XML of another kind, and a program without a MainProgram
  gz = urp_test_gzip("<Installation name=\"default\"/>", &len);
  assert_int_equal(urt_urp_compile(gz, len, NULL, &p, why, sizeof why), -1);
  assert_string_equal(why, "not a PolyScope program (root element 'Installation')");
  free(gz);
  gz = urp_test_gzip("<URProgram name=\"x\"><children><InitVariablesNode/></children></URProgram>",
                     &len);
  assert_int_equal(urt_urp_compile(gz, len, NULL, &p, why, sizeof why), -1);
  assert_string_equal(why, "no MainProgram");
  free(gz);

  // nesting deeper than the bound
  size_t depth = 400, cap = depth * 24 + 64;
  char *deep = malloc(cap);
  size_t n = 0;
  for (size_t k = 0; k < depth; k++) n += (size_t)snprintf(deep + n, cap - n, "<Folder>");
  for (size_t k = 0; k < depth; k++) n += (size_t)snprintf(deep + n, cap - n, "</Folder>");
  gz = urp_test_gzip(deep, &len);
  assert_int_equal(urt_urp_compile(gz, len, NULL, &p, why, sizeof why), -1);
  assert_non_null(strstr(why, "nested deeper"));
  free(gz);
  free(deep);

  // a missing file
  assert_int_equal(urt_urp_compile_file("/nonexistent/x.urp", NULL, &p, why, sizeof why), -1);
  assert_non_null(strstr(why, "cannot open"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_urcl_wait_program),
      cmocka_unit_test(test_urcl_external_control),
      cmocka_unit_test(test_move_j_l_p),
      cmocka_unit_test(test_wait_and_set),
      cmocka_unit_test(test_script_line_and_file),
      cmocka_unit_test(test_assignment_and_expressions),
      cmocka_unit_test(test_loops),
      cmocka_unit_test(test_if_elseif_else),
      cmocka_unit_test(test_folder_comment_popup_halt),
      cmocka_unit_test(test_before_start_and_loop_forever),
      cmocka_unit_test(test_external_control_slots),
      cmocka_unit_test(test_unsupported_nodes),
      cmocka_unit_test(test_bad_values),
      cmocka_unit_test(test_bad_files),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
