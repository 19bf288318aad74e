/* canemu_speedups: the python-can interface's send hot path in C (docs/python.md, "Measured").
 *
 * CanemuBus.send() puts a classic data frame of 0..8 bytes into the transmit FIFO through
 * canChannelPostMessage of libvcinpl2.so. In Python that is some 0.6 us a frame: the message's
 * attributes, the CANMSG2 packed by struct, the lock, the ctypes call. A ClassicPoster does the
 * same in one call of about a third of that, and says whether the frame went into the FIFO;
 * anything else (another kind of frame, a full FIFO, an error, a closed channel) it leaves to
 * send()'s Python path, which then does what it always did. It is built against the stable ABI
 * (Python 3.10 and later) and found beside libvcinpl2.so or installed with the package; without
 * it the Python path does everything.
 *
 * Threads: a post holds the GIL from the look at the handle to the library's return, so it runs
 * either wholly before or wholly after close(), which the bus calls before it closes the
 * channel. */
#define Py_LIMITED_API 0x030A0000
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>

/* HRESULT canChannelPostMessage(HANDLE hCanChn, PCANMSG2 pCanMsg) */
typedef int32_t (*PostFn)(void* channel, void* message);

/* CANMSG2 as send()'s struct "<8xI2xB1x8s56x" writes a classic data frame: dwTime and
 * dwReserved 0 (at once), dwMsgId, bType CAN_MSGTYPE_DATA (0), bFlags2 0, bFlags, bAccept 0,
 * abData[64]. */
enum { kMessageSize = 80, kIdAt = 8, kFlagsAt = 14, kDataAt = 16 };

typedef struct {
  PyObject ob_base; /* PyObject_HEAD */
  PostFn post;
  void* channel;     /* NULL once closed */
  uint8_t flags;     /* bFlags bits of an 11-bit frame besides the DLC (SRR) */
  uint8_t flags_ext; /* those of a 29-bit frame (EXT, SRR) */
} ClassicPoster;

static PyObject* s_is_error_frame;
static PyObject* s_is_fd;
static PyObject* s_is_remote_frame;
static PyObject* s_is_extended_id;
static PyObject* s_arbitration_id;
static PyObject* s_data;

/* The attribute `name` of `msg` is true: 1, false: 0, error: -1. */
static int flag_of(PyObject* msg, PyObject* name) {
  PyObject* v = PyObject_GetAttr(msg, name);
  if (v == NULL) {
    return -1;
  }
  const int r = PyObject_IsTrue(v);
  Py_DECREF(v);
  return r;
}

static int poster_init(PyObject* self, PyObject* args, PyObject* kwargs) {
  ClassicPoster* p = (ClassicPoster*)self;
  unsigned long long post = 0;
  unsigned long long channel = 0;
  unsigned char flags = 0;
  unsigned char flags_ext = 0;
  static char* names[] = {"post", "channel", "flags", "flags_ext", NULL};
  if (!PyArg_ParseTupleAndKeywords(args, kwargs, "KKbb", names, &post, &channel, &flags,
                                   &flags_ext)) {
    return -1;
  }
  if (post == 0 || channel == 0) {
    PyErr_SetString(PyExc_ValueError,
                    "ClassicPoster needs the function's and the channel's address");
    return -1;
  }
  p->post = (PostFn)(uintptr_t)post;
  p->channel = (void*)(uintptr_t)channel;
  p->flags = flags;
  p->flags_ext = flags_ext;
  return 0;
}

/* post(msg) -> bool: whether `msg` went into the transmit FIFO. False, with nothing done, for
 * what send()'s Python path handles: error, CAN FD and remote frames, more than 8 bytes, an
 * identifier beyond its format, data that is neither bytes nor bytearray; false too when the
 * library did not take it (full FIFO, error: the Python path posts again and says why). */
static PyObject* poster_post(PyObject* self, PyObject* const* args, Py_ssize_t nargs) {
  ClassicPoster* p = (ClassicPoster*)self;
  if (nargs != 1) {
    PyErr_SetString(PyExc_TypeError, "post() takes one message");
    return NULL;
  }
  PyObject* msg = args[0];
  if (p->channel == NULL) {
    Py_RETURN_FALSE;
  }
  int error_frame = flag_of(msg, s_is_error_frame);
  int fd = error_frame == 0 ? flag_of(msg, s_is_fd) : error_frame;
  int remote = fd == 0 ? flag_of(msg, s_is_remote_frame) : fd;
  if (remote != 0) {
    if (remote < 0) {
      PyErr_Clear(); /* not a python-can Message: the Python path says so */
    }
    Py_RETURN_FALSE;
  }
  const int ext = flag_of(msg, s_is_extended_id);
  PyObject* id_obj = PyObject_GetAttr(msg, s_arbitration_id);
  if (ext < 0 || id_obj == NULL) {
    Py_XDECREF(id_obj);
    PyErr_Clear();
    Py_RETURN_FALSE;
  }
  const unsigned long long id = PyLong_AsUnsignedLongLong(id_obj);
  Py_DECREF(id_obj);
  if (PyErr_Occurred() != NULL || id > (ext ? 0x1FFFFFFFull : 0x7FFull)) {
    PyErr_Clear(); /* negative, not an int, too large */
    Py_RETURN_FALSE;
  }
  PyObject* data = PyObject_GetAttr(msg, s_data);
  if (data == NULL) {
    PyErr_Clear();
    Py_RETURN_FALSE;
  }
  const char* bytes = NULL;
  Py_ssize_t length = 0;
  if (PyByteArray_Check(data)) {
    bytes = PyByteArray_AsString(data);
    length = PyByteArray_Size(data);
  } else if (PyBytes_Check(data)) {
    bytes = PyBytes_AsString(data);
    length = PyBytes_Size(data);
  }
  if (bytes == NULL || length > 8) {
    Py_DECREF(data);
    PyErr_Clear();
    Py_RETURN_FALSE;
  }
  uint8_t m[kMessageSize];
  memset(m, 0, sizeof m);
  const uint32_t id32 = (uint32_t)id;
  memcpy(m + kIdAt, &id32, 4); /* in the byte order of the library's CANMSG2 (the host's) */
  m[kFlagsAt] = (uint8_t)(length | (ext ? p->flags_ext : p->flags));
  memcpy(m + kDataAt, bytes, (size_t)length);
  Py_DECREF(data);
  if (p->post(p->channel, m) != 0) {
    Py_RETURN_FALSE;
  }
  Py_RETURN_TRUE;
}

/* close(): the channel is about to be closed; every post from now on is left to Python. */
static PyObject* poster_close(PyObject* self, PyObject* unused) {
  (void)unused;
  ((ClassicPoster*)self)->channel = NULL;
  Py_RETURN_NONE;
}

static PyMethodDef poster_methods[] = {
    {"post", (PyCFunction)(void (*)(void))poster_post, METH_FASTCALL,
     "post(msg) -> bool: msg into the transmit FIFO, if it is a classic data frame it takes"},
    {"close", poster_close, METH_NOARGS, "close(): no post from now on"},
    {NULL, NULL, 0, NULL},
};

static PyType_Slot poster_slots[] = {
    {Py_tp_init, poster_init},
    {Py_tp_new, PyType_GenericNew},
    {Py_tp_methods, poster_methods},
    {Py_tp_doc, "ClassicPoster(post, channel, flags, flags_ext): send()'s hot path"},
    {0, NULL},
};

static PyType_Spec poster_spec = {
    "canemu_speedups.ClassicPoster", sizeof(ClassicPoster), 0, Py_TPFLAGS_DEFAULT, poster_slots,
};

static int module_exec(PyObject* module) {
  static const char* const names[] = {"is_error_frame", "is_fd",          "is_remote_frame",
                                      "is_extended_id", "arbitration_id", "data"};
  PyObject** slots[] = {&s_is_error_frame, &s_is_fd,          &s_is_remote_frame,
                        &s_is_extended_id, &s_arbitration_id, &s_data};
  for (size_t k = 0; k < sizeof slots / sizeof slots[0]; ++k) {
    if (*slots[k] == NULL && (*slots[k] = PyUnicode_InternFromString(names[k])) == NULL) {
      return -1;
    }
  }
  PyObject* type = PyType_FromSpec(&poster_spec);
  if (type == NULL) {
    return -1;
  }
  if (PyModule_AddObject(module, "ClassicPoster", type) < 0) {
    Py_DECREF(type);
    return -1;
  }
  return 0;
}

static PyModuleDef_Slot module_slots[] = {
    {Py_mod_exec, module_exec},
    {0, NULL},
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT,
    "canemu_speedups",
    "The python-can interface's send hot path in C (docs/python.md, \"Measured\").",
    0,
    NULL,
    module_slots,
    NULL,
    NULL,
    NULL,
};

PyMODINIT_FUNC PyInit_canemu_speedups(void) {
  return PyModuleDef_Init(&module_def);
}
